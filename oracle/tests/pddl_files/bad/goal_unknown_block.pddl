; expect: line 6: (on b1 b9) names b9, which :objects does not declare
(define (problem goal-unknown-block) (:domain blocksworld)
 (:objects b1 b2)
 (:init (arm-empty) (clear b1) (clear b2) (on-table b1) (on-table b2))
 (:goal (and
   (on b1 b9))))
