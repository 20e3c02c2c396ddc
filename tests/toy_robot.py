"""A toy robot for the tests: the Panda with its third joint locked, a six-joint arm.

Adding a robot is data: a ``RobotDescription`` and the builders of its two models, here
written in the tests, with no core module touched.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import mujoco

from osg_control.control.description import ArmJoints, ModelSource, ServoGains
from osg_control.control.robot_model import find_example_robot_data, reduced_urdf_model
from osg_control.robots.panda import FINGER_JOINTS, PANDA, URDF, panda_mujoco_spec

LOCKED = 2
"""The toy arm is the Panda with its third joint locked at 0 (its home value): six joints."""


def _unlocked(values: tuple[Any, ...]) -> tuple[Any, ...]:
    return tuple(v for i, v in enumerate(values) if i != LOCKED)


def _toy_mujoco() -> mujoco.MjSpec:
    spec = panda_mujoco_spec()
    spec.delete(spec.joint(PANDA.arm.names[LOCKED]))
    return spec


def _toy_pinocchio() -> Any:
    locked = (*FINGER_JOINTS, PANDA.arm.names[LOCKED])
    return reduced_urdf_model(find_example_robot_data(URDF), locked)


ARM = PANDA.arm
TOY = dataclasses.replace(
    PANDA,
    name="toy6",
    summary="the Panda with joint 3 locked: a six-joint arm, defined in a test",
    model=ModelSource(mujoco=_toy_mujoco, pinocchio=_toy_pinocchio),
    arm=ArmJoints(*(_unlocked(getattr(ARM, f.name)) for f in dataclasses.fields(ARM))),
    servo=ServoGains(_unlocked(PANDA.servo.kp), _unlocked(PANDA.servo.kv)),
    home_q=_unlocked(PANDA.home_q),
)
"""A new robot: data and two model builders, no core module touched."""
