"""robosuite's Panda, the arm of every LIBERO scene, as a ``RobotDescription``: both models
built from robosuite's own MJCF (its ``Panda`` with its ``PandaGripper``, the names the
scenes use: ``robot0_joint1`` ..., ``gripper0_*``), limits and home posture read from it.

The scene decides where it stands: ``scene_mount`` reads the base's pose from a LIBERO
env's model (static scene geometry, read once to set up, never to decide). LIBERO's own
controller drives it in the scenes (``env.CONTROLLER``); the description is what our IK
needs (``drive.JointTargetDriver``). Needs the ``libero`` extra.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import mujoco
import numpy as np

from osg_control.control.description import (
    ArmJoints,
    Gripper,
    ModelSource,
    Placement,
    RobotDescription,
    ServoGains,
    TcpFrame,
    mounted,
)
from osg_control.control.mujoco_pinocchio import pinocchio_arm_from_mujoco
from osg_control.libero.extra import require_libero
from osg_control.robots.panda import PANDA

ARM_JOINTS = tuple(f"robot0_joint{i}" for i in range(1, 8))
FINGER_JOINTS = ("gripper0_finger_joint1", "gripper0_finger_joint2")
FINGER_BODIES = ("gripper0_leftfinger", "gripper0_rightfinger")
BASE_BODY = "robot0_base"
TCP_BODY = "gripper0_eef"
"""The body of robosuite's ``grip_site`` (``robot0_eef_pos`` in LIBERO's observation)."""
TCP_FRAME = "gripper0_tcp"
TCP_QUAT = (math.cos(-math.pi / 4), 0.0, 0.0, math.sin(-math.pi / 4))
"""The grip site's frame turned -90 deg about its z axis (the approach, pointing out of the
hand): its y axis is then the fingers' sliding direction (the tool convention)."""
TCP = TcpFrame(body=TCP_BODY, pos=(0.0, 0.0, 0.0), quat=TCP_QUAT, frame=TCP_FRAME)
"""The TCP in both models."""


@cache
def _mjcf() -> str:
    """robosuite's Panda with its gripper as one MJCF (absolute mesh paths), its angles
    declared in radians (robosuite sets that in the scene's file, not the robot's)."""
    robots = require_libero("robosuite.models.robots")
    grippers = require_libero("robosuite.models.grippers")
    robot = robots.Panda(idn=0)
    robot.add_gripper(grippers.PandaGripper(idn=0))
    head, body = str(robot.get_xml()).split(">", 1)
    return f'{head}>\n    <compiler angle="radian"/>{body}'


def libero_panda_spec() -> mujoco.MjSpec:
    """The bare Panda (no actuators: the core adds its own), the second finger coupled to
    the first as robosuite's gripper drives them (mirrored)."""
    spec = mujoco.MjSpec.from_string(_mjcf())
    for actuator in list(spec.actuators):
        spec.delete(actuator)
    spec.add_equality(
        type=mujoco.mjtEq.mjEQ_JOINT,
        name1=FINGER_JOINTS[1],
        name2=FINGER_JOINTS[0],
        data=[0.0, -1.0] + [0.0] * 10,  # joint2 = -joint1
    )
    return spec


def libero_panda_pinocchio() -> Any:
    """The arm-only Pinocchio model of the same MJCF compiled (``control.mujoco_pinocchio``;
    fingers welded), with the TCP frame ``TCP_FRAME`` and the description's velocity limits
    (MJCF has none)."""
    model = mujoco.MjSpec.from_string(_mjcf()).compile()
    return pinocchio_arm_from_mujoco(model, ARM_JOINTS, TCP, velocity=PANDA.arm.velocity)


def _limits() -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
    """Lower and upper joint limits and motor torque limits, from robosuite's MJCF."""
    spec = mujoco.MjSpec.from_string(_mjcf())
    model = spec.compile()
    ranges = np.array([model.joint(j).range for j in ARM_JOINTS])
    effort = [float(model.actuator(f"robot0_torq_j{i}").ctrlrange[1]) for i in range(1, 8)]
    return tuple(ranges[:, 0].tolist()), tuple(ranges[:, 1].tolist()), tuple(effort)


@cache
def libero_panda() -> RobotDescription:
    """robosuite's Panda at the origin (``mounted`` with ``scene_mount`` for a scene).

    Its joint limits, motor torque limits and home posture (robosuite's ``init_qpos``) are
    robosuite's; its speed limits and servo gains are the Franka data sheet's and our Panda's
    (``robots.panda``), used only where our own simulation drives it.
    """
    lower, upper, effort = _limits()
    init_qpos = require_libero("robosuite.models.robots").Panda(idn=0).init_qpos
    return RobotDescription(
        name="libero-panda",
        summary="robosuite 1.4's Panda (LIBERO's arm), 7 joints, Panda gripper",
        model=ModelSource(mujoco=libero_panda_spec, pinocchio=libero_panda_pinocchio),
        arm=ArmJoints(
            names=ARM_JOINTS,
            lower=lower,
            upper=upper,
            velocity=PANDA.arm.velocity,
            effort=effort,
            armature=PANDA.arm.armature,
        ),
        servo=ServoGains(kp=PANDA.servo.kp, kv=PANDA.servo.kv),
        tcp=TCP,
        gripper=Gripper(
            joints=(FINGER_JOINTS[0],),
            bodies=FINGER_BODIES,
            open_position=0.04,
            kp=PANDA.gripper.kp,
            kv=PANDA.gripper.kv,
            force=PANDA.gripper.force,
            width_scale=2.0,  # the second finger mirrors the first
        ),
        home_q=tuple(float(q) for q in init_qpos),
        control_hz=20.0,
    )


def scene_mount(sim: Any) -> Placement:
    """Where the arm's base stands in a LIBERO scene (its ``MjSim``)."""
    model = sim.model._model
    body = model.body(BASE_BODY)
    pos, quat = body.pos.tolist(), body.quat.tolist()
    return (pos[0], pos[1], pos[2]), (quat[0], quat[1], quat[2], quat[3])


def mounted_panda(sim: Any) -> RobotDescription:
    """robosuite's Panda where the scene stands it."""
    return mounted(libero_panda(), scene_mount(sim))
