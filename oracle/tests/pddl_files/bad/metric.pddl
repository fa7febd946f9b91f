; expect: the metric (:metric maximize (total-cost)) is not read: blockstack minimizes the number of actions
(define (problem metric) (:domain blocksworld)
 (:objects b1)
 (:init (arm-empty) (clear b1) (on-table b1))
 (:goal (and (on-table b1)))
 (:metric maximize (total-cost)))
