; expect: line 3: (:domain logistics) is not the Blocks World, the one domain blockstack plans
(define (problem other-domain)
 (:domain logistics)
 (:objects b1)
 (:init (arm-empty) (clear b1) (on-table b1))
 (:goal (and (on-table b1))))
