; expect: line 4: unknown predicate table-top in (table-top b1): the 4-operator Blocks World has on, on-table, clear, arm-empty and holding
(define (problem unknown-predicate) (:domain blocks)
 (:objects b1)
 (:init (arm-empty) (clear b1) (table-top b1))
 (:goal (and (on-table b1))))
