; expect: it is not UTF-8 text
(define (problem ÿ) )
