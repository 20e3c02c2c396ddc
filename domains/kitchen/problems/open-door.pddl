; slide the cabinet door open and let go of the handle; from home with door-closed cube-on-counter hand-empty valve-closed
(define (problem open-door)
    (:domain osg-kitchen)
    (:requirements :action-costs :strips :typing)
    (:init (= (total-cost) 0) (at home) (cube-on-counter) (door-closed) (hand-empty) (valve-closed))
    (:goal (and (door-open) (hand-empty)))
    (:metric minimize (total-cost))
)
