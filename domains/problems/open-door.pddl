; slide the cabinet door open; from home with door-closed cube-on-counter hand-empty
(define (problem open-door)
    (:domain osg-kitchen)
    (:requirements :action-costs :strips :typing)
    (:init (= (total-cost) 0) (at home) (cube-on-counter) (door-closed) (hand-empty))
    (:goal (door-open))
    (:metric minimize (total-cost))
)
