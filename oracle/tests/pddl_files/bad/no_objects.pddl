; expect: the problem declares no blocks in :objects
(define (problem empty) (:domain blocksworld)
 (:objects)
 (:init (arm-empty))
 (:goal (and)))
