; expect: the section (:metric minimize (total-cost)) is not read
(define (problem metric) (:domain blocksworld)
 (:objects b1)
 (:init (arm-empty) (clear b1) (on-table b1))
 (:goal (and (on-table b1)))
 (:metric minimize (total-cost)))
