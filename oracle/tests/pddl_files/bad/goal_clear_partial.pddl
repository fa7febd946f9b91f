; expect: the goal says (clear b2) but does not place every block
(define (problem goal-clear) (:domain blocksworld)
 (:objects b1 b2 b3)
 (:init (arm-empty) (clear b1) (clear b2) (clear b3) (on-table b1) (on-table b2) (on-table b3))
 (:goal (and (on b2 b1) (on-table b1) (clear b2))))
