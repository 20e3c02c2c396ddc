; D4RL kitchen-complete: microwave, kettle, light switch, slide cabinet; from home with hand-empty microwave-closed kettle-home light-off slide-closed hinge-closed bottom-burner-off top-burner-off
(define (problem kitchen-complete)
    (:domain osg-franka-kitchen)
    (:requirements :action-costs :strips :typing)
    (:init (= (total-cost) 0) (at home) (bottom-burner-off) (hand-empty) (hinge-closed) (kettle-home) (light-off) (microwave-closed) (slide-closed) (top-burner-off))
    (:goal (and (microwave-open) (kettle-moved) (light-on) (slide-open)))
    (:metric minimize (total-cost))
)
