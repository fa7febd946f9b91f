; What other tools write: the 2000 competition's ontable and handempty, (either ...) types,
; a unit-cost metric and its initial cost. Blocks: a (0), b (1); b stands on a, goal a on b.
(define (problem other-tools) (:domain BLOCKS)
 (:objects a - block b - (either block thing))
 (:init (= (total-cost) 0) (handempty) (clear b) (on b a) (ontable a))
 (:goal (and (on a b) (ontable b)))
 (:metric minimize (total-cost)))
