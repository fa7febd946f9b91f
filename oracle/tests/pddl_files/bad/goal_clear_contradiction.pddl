; expect: the goal says (clear b1) and puts b2 on it
(define (problem goal-clear) (:domain blocksworld)
 (:objects b1 b2)
 (:init (arm-empty) (clear b1) (clear b2) (on-table b1) (on-table b2))
 (:goal (and (on b2 b1) (on-table b1) (clear b1) (clear b2))))
