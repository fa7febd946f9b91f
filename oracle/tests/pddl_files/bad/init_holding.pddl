; expect: the init holds b1: blockstack plans from a state with the arm empty
(define (problem holding) (:domain blocksworld)
 (:objects b1 b2)
 (:init (holding b1) (clear b2) (on-table b2))
 (:goal (and (on b1 b2) (on-table b2))))
