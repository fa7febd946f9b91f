; expect: the goal's on facts form a cycle: b1 on b2 on b1
(define (problem goal-cycle) (:domain blocksworld)
 (:objects b1 b2)
 (:init (arm-empty) (clear b1) (clear b2) (on-table b1) (on-table b2))
 (:goal (and (on b1 b2) (on b2 b1))))
