; expect: the goal puts b1 on b2 but does not say what b2 stands on
(define (problem pddlgym-style) (:domain blocks)
 (:objects b1 b2 b3)
 (:init (arm-empty) (clear b1) (clear b2) (clear b3) (on-table b1) (on-table b2) (on-table b3))
 (:goal (and (on b1 b2) (on b3 b1))))
