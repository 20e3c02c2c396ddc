; push the valve's lever round by about 1 rad (nothing is grasped); from home with door-closed cube-on-counter hand-empty valve-closed
(define (problem turn-valve)
    (:domain osg-kitchen)
    (:requirements :action-costs :strips :typing)
    (:init (= (total-cost) 0) (at home) (cube-on-counter) (door-closed) (hand-empty) (valve-closed))
    (:goal (and (valve-open) (hand-empty)))
    (:metric minimize (total-cost))
)
