; expect: the init says (clear b2) but b1 stands on it
(define (problem clear-wrong) (:domain blocksworld)
 (:objects b1 b2)
 (:init (arm-empty) (clear b1) (clear b2) (on b1 b2) (on-table b2))
 (:goal (and (on-table b1))))
