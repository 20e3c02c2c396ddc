; slide the cabinet door open, let go of the handle, turn the valve; from home with door-closed cube-on-counter hand-empty valve-closed
(define (problem open-door-turn-valve)
    (:domain osg-kitchen)
    (:requirements :action-costs :strips :typing)
    (:init (= (total-cost) 0) (at home) (cube-on-counter) (door-closed) (hand-empty) (valve-closed))
    (:goal (and (door-open) (valve-open) (hand-empty)))
    (:metric minimize (total-cost))
)
