; Upper-case keywords and names, no space between facts, typed objects, requirements:
; legal PDDL that other tools write. Blocks: C (0), A (1), B (2).
(DEFINE (PROBLEM BLOCKS-3-0) (:DOMAIN BLOCKSWORLD)
 (:requirements :strips :typing)
 (:OBJECTS C A - block B - block)
 (:INIT (ARM-EMPTY)(CLEAR C)(CLEAR A)(ON A B)(ON-TABLE B)(ON-TABLE C))
 (:goal (AND (ON C B)(ON B A) (ON-TABLE A))))
