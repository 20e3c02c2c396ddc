"""A domain's scene with a robot attached at the origin and its ``HOME_KEY`` keyframe.

Every ``ArmEnv`` resets from a full-state keyframe named ``robot_model.HOME_KEY``: the arm at
its home posture, the fingers open, every scene joint at its rest value. A domain's
``build_model`` is ``home_keyed_model(with_robot(MjSpec.from_file(...), robot), robot)``.
"""

from __future__ import annotations

import warnings

import mujoco
import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.control.robot_model import GRIPPER_ACTUATOR, HOME_KEY, robot_spec
from osg_control.control.servo import add_speed_sensors

_EMPTY_PREFIX = "Attaching a spec with an empty prefix"
"""MuJoCo's warning for ``attach(prefix="")``: the robot's URDF names are unique in a scene,
so no prefix is needed."""


def with_robot(scene: mujoco.MjSpec, robot: RobotDescription) -> mujoco.MjSpec:
    """Attach ``robot`` (gripper included, its own keyframes dropped: the scene's keyframe
    must cover the scene's joints too) at the world origin of ``scene``, with its joints'
    speed sensors keeping one control step of substeps (``servo.SpeedWatch``); returns
    ``scene``."""
    robot_model = robot_spec(robot, with_gripper=True)
    for key in list(robot_model.keys):
        robot_model.delete(key)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=_EMPTY_PREFIX)
        scene.attach(robot_model, frame=scene.worldbody.add_frame(), prefix="")
    add_speed_sensors(scene, robot.arm.names, robot.substeps(scene.option.timestep))
    return scene


def home_keyed_model(spec: mujoco.MjSpec, robot: RobotDescription) -> mujoco.MjModel:
    """Compile ``spec`` with a full-state ``HOME_KEY`` keyframe: scene joints at their rest
    values (qpos0), the arm at its home posture and the fingers open, servos holding there."""
    model = _compile(spec)
    qpos = mujoco.MjData(model).qpos.copy()
    ctrl = np.zeros(model.nu)
    for name, value in zip(robot.arm.names, robot.home_q, strict=True):
        qpos[model.joint(name).qposadr[0]] = value
        ctrl[model.actuator(name).id] = value
    opening = robot.gripper.open_position
    for name in robot.gripper.joints:
        qpos[model.joint(name).qposadr[0]] = opening
    ctrl[model.actuator(GRIPPER_ACTUATOR).id] = opening
    spec.add_key(name=HOME_KEY, qpos=qpos, ctrl=ctrl)
    return _compile(spec)


def _compile(spec: mujoco.MjSpec) -> mujoco.MjModel:
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=_EMPTY_PREFIX)
        return spec.compile()
