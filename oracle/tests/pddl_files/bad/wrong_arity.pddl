; expect: (on b1) takes 2 block(s), not 1
(define (problem arity) (:domain blocksworld)
 (:objects b1 b2)
 (:init (arm-empty) (clear b1) (on b1) (on-table b2))
 (:goal (and (on-table b1))))
