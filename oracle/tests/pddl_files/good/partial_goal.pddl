; A goal that places two of four blocks: b3 and b4 are free. Duplicate facts are one fact.
(define (problem partial) (:domain blocksworld)
 (:objects b1 b2 b3 b4)
 (:init (arm-empty) (clear b1) (on b1 b2) (on b2 b3) (on-table b3) (clear b4) (on-table b4) (clear b4))
 (:goal (and (on b2 b1) (on-table b1) (arm-empty))))
