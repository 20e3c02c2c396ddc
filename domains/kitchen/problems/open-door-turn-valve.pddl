; slide the cabinet door open, let go of the handle, turn the valve; from home with door-closed cube-on-counter hand-empty valve-closed
(define (problem open-door-turn-valve)
    (:domain osg-kitchen)
    (:requirements :action-costs :strips :typing)
    (:objects cube-1 - cube valve-1 - valve)
    (:init (= (total-cost) 0) (at home) (door-closed door-1) (hand-empty) (on-counter cube-1) (valve-closed valve-1))
    (:goal (and (door-open door-1) (valve-open valve-1) (hand-empty)))
    (:metric minimize (total-cost))
)
