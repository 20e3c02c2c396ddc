"""Control layer: the robot model, differential IK and the TCP estimator."""
