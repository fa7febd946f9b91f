; expect: two blocks stand on b3 in the init: b1 (line 4) and b2
(define (problem two-on-one) (:domain blocksworld)
 (:objects b1 b2 b3)
 (:init (arm-empty) (clear b1) (clear b2) (on b1 b3)
   (on b2 b3) (on-table b3))
 (:goal (and (on-table b1))))
