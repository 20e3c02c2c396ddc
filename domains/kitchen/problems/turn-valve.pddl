; push the valve's lever round by about 1 rad (nothing is grasped); from home with door-closed cube-on-counter hand-empty valve-closed
(define (problem turn-valve)
    (:domain osg-kitchen)
    (:requirements :action-costs :strips :typing)
    (:objects cube-1 - cube valve-1 - valve)
    (:init (= (total-cost) 0) (at home) (door-closed door-1) (hand-empty) (on-counter cube-1) (valve-closed valve-1))
    (:goal (and (valve-open valve-1) (hand-empty)))
    (:metric minimize (total-cost))
)
