"""A domain's scene with the Panda attached at the origin and its ``HOME_KEY`` keyframe.

Every ``ArmEnv`` resets from a full-state keyframe named ``robot.HOME_KEY``: the arm at
``HOME_Q``, the fingers open, every scene joint at its rest value. A domain's
``build_model`` is ``home_keyed_model(with_panda(MjSpec.from_file(...)))``.
"""

from __future__ import annotations

import warnings

import mujoco
import numpy as np

from osg_control.control.robot import (
    ARM_JOINTS,
    FINGER_JOINTS,
    FINGER_OPEN,
    HOME_KEY,
    HOME_Q,
    panda_spec,
    substeps_per_control_step,
)
from osg_control.control.servo import add_speed_sensors

_EMPTY_PREFIX = "Attaching a spec with an empty prefix"
"""MuJoCo's warning for ``attach(prefix="")``: the robot's URDF names are unique in a scene,
so no prefix is needed."""


def with_panda(scene: mujoco.MjSpec) -> mujoco.MjSpec:
    """Attach the Panda (fingers included, its own keyframes dropped: the scene's keyframe
    must cover the scene's joints too) at the world origin of ``scene``, with its joints'
    speed sensors keeping one control step of substeps (``servo.SpeedWatch``); returns
    ``scene``."""
    robot = panda_spec(with_fingers=True)
    for key in list(robot.keys):
        robot.delete(key)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=_EMPTY_PREFIX)
        scene.attach(robot, frame=scene.worldbody.add_frame(), prefix="")
    add_speed_sensors(scene, ARM_JOINTS, substeps_per_control_step(scene.option.timestep))
    return scene


def home_keyed_model(spec: mujoco.MjSpec) -> mujoco.MjModel:
    """Compile ``spec`` with a full-state ``HOME_KEY`` keyframe: scene joints at their rest
    values (qpos0), the arm at ``HOME_Q`` and the fingers open, servos holding there."""
    model = _compile(spec)
    qpos = mujoco.MjData(model).qpos.copy()
    ctrl = np.zeros(model.nu)
    for name, value in zip(ARM_JOINTS, HOME_Q, strict=True):
        qpos[model.joint(name).qposadr[0]] = value
        ctrl[model.actuator(name).id] = value
    for name in FINGER_JOINTS:
        qpos[model.joint(name).qposadr[0]] = FINGER_OPEN
    ctrl[model.actuator("gripper").id] = FINGER_OPEN
    spec.add_key(name=HOME_KEY, qpos=qpos, ctrl=ctrl)
    return _compile(spec)


def _compile(spec: mujoco.MjSpec) -> mujoco.MjModel:
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=_EMPTY_PREFIX)
        return spec.compile()
