; expect: object B1 is declared twice (first on line 3)
(define (problem twice) (:domain blocksworld)
 (:objects b1
  B1)
 (:init (arm-empty) (clear b1) (on-table b1))
 (:goal (and (on-table b1))))
