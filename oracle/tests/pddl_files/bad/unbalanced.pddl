; expect: line 2: this '(' is never closed
(define (problem unbalanced) (:domain blocksworld)
 (:objects b1)
 (:init (arm-empty) (clear b1) (on-table b1))
 (:goal (and (on-table b1)))
