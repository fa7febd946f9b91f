; expect: line 4: unknown predicate ontable in (ontable b1): the 4-operator Blocks World has on, on-table, clear, arm-empty and holding
(define (problem unknown-predicate) (:domain blocks)
 (:objects b1)
 (:init (arm-empty) (clear b1) (ontable b1))
 (:goal (and (on-table b1))))
