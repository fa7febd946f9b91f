; expect: this is a domain file: give the problem file
(define (domain blocksworld)
 (:requirements :strips)
 (:predicates (clear ?x) (on-table ?x) (arm-empty) (holding ?x) (on ?x ?y)))
