; open the door, pick the cube up, place it in the cabinet; from home with door-closed cube-on-counter hand-empty valve-closed
(define (problem open-pick-up-place)
    (:domain osg-kitchen)
    (:requirements :action-costs :strips :typing)
    (:init (= (total-cost) 0) (at home) (cube-on-counter) (door-closed) (hand-empty) (valve-closed))
    (:goal (and (door-open) (cube-in-cabinet)))
    (:metric minimize (total-cost))
)
