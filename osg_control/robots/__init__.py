"""Robots: one module per robot, each a ``control.description.RobotDescription`` and the
builders of its models, found by name through ``registry.get_robot``. The only package
besides the domains that may name a robot."""
