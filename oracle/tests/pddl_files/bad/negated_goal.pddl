; expect: (not (on b1 b2)) in the goal: a Blocks World goal is a list of facts
(define (problem negated) (:domain blocksworld)
 (:objects b1 b2)
 (:init (arm-empty) (clear b1) (clear b2) (on-table b1) (on-table b2))
 (:goal (and (not (on b1 b2)))))
