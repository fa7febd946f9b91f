; expect: (on b1 b1): a block cannot stand on itself
(define (problem on-itself) (:domain blocksworld)
 (:objects b1)
 (:init (arm-empty) (clear b1) (on b1 b1))
 (:goal (and (on-table b1))))
