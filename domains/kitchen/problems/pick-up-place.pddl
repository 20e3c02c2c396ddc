; door already open: pick the cube up and place it in the cabinet; from home with door-open cube-on-counter hand-empty valve-closed
(define (problem pick-up-place)
    (:domain osg-kitchen)
    (:requirements :action-costs :strips :typing)
    (:init (= (total-cost) 0) (at home) (cube-on-counter) (door-open) (hand-empty) (valve-closed))
    (:goal (cube-in-cabinet))
    (:metric minimize (total-cost))
)
