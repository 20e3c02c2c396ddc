"""Robot models: each robot's description files, MuJoCo spec and Pinocchio model."""
