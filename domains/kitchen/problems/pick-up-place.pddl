; door already open: pick the cube up and place it in the cabinet; from home with door-open cube-on-counter hand-empty valve-closed
(define (problem pick-up-place)
    (:domain osg-kitchen)
    (:requirements :action-costs :strips :typing)
    (:objects cube-1 - cube valve-1 - valve)
    (:init (= (total-cost) 0) (at home) (door-open door-1) (hand-empty) (on-counter cube-1) (valve-closed valve-1))
    (:goal (in-cabinet cube-1))
    (:metric minimize (total-cost))
)
