; expect: the init's on facts form a cycle: b1 on b2 on b3 on b1
(define (problem cycle) (:domain blocksworld)
 (:objects b1 b2 b3 b4)
 (:init (arm-empty) (clear b4) (on-table b4)
   (on b1 b2) (on b2 b3) (on b3 b1))
 (:goal (and (on-table b1))))
