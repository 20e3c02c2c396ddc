; open the door, pick the cube up, place it in the cabinet; from home with door-closed cube-on-counter hand-empty valve-closed
(define (problem open-pick-up-place)
    (:domain osg-kitchen)
    (:requirements :action-costs :strips :typing)
    (:objects cube-1 - cube valve-1 - valve)
    (:init (= (total-cost) 0) (at home) (door-closed door-1) (hand-empty) (on-counter cube-1) (valve-closed valve-1))
    (:goal (and (door-open door-1) (in-cabinet cube-1)))
    (:metric minimize (total-cost))
)
