"""Our differential IK driving LIBERO's arm through robosuite's ``JOINT_POSITION``
controller: each step, the IK's next joint target from the observed joint positions becomes
the controller's joint delta.

The IK's joint speeds are capped so one step's delta never exceeds what the controller
takes (``env.JOINT_DELTA_LIMIT``): the QP, not a clip afterwards, keeps the motion's
direction.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.control.ik import DiffIKController
from osg_control.control.ik_backends import IKConfig
from osg_control.libero.env import JOINT_DELTA_LIMIT

JOINTS_OBS = "robot0_joint_pos"
TCP_OBS = "robot0_eef_pos"
GRIPPER_OPEN, GRIPPER_CLOSED = -1.0, 1.0
"""robosuite's gripper commands."""


class JointTargetDriver:
    """TCP targets -> LIBERO ``JOINT_POSITION`` actions (7 scaled joint deltas + gripper).

    Args:
        robot: the arm where the scene stands it (``robot.mounted_panda``).
        config: the IK's weights and backend; its ``dt`` must be the env's control period
            and its ``velocity_scale`` is set from ``JOINT_DELTA_LIMIT``.
    """

    def __init__(self, robot: RobotDescription, config: IKConfig | None = None) -> None:
        base = config or IKConfig(dt=1.0 / robot.control_hz)
        scale = JOINT_DELTA_LIMIT / (base.dt * max(robot.arm.velocity))
        self.ik = DiffIKController(robot, replace(base, velocity_scale=min(1.0, scale)))

    def action(
        self,
        joints: np.ndarray,
        target_pos: np.ndarray,
        target_rot: np.ndarray,
        gripper: float = GRIPPER_OPEN,
    ) -> np.ndarray:
        """The action that moves the TCP toward ``target_pos`` and ``target_rot`` (world
        frame) from the perceived joints (``robot0_joint_pos``), with the gripper command."""
        q = np.asarray(joints, dtype=float)
        delta = self.ik.step(q, target_pos, target_rot) - q
        return np.r_[np.clip(delta / JOINT_DELTA_LIMIT, -1.0, 1.0), gripper]

    def tcp_pose(self, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The TCP pose (position, rotation) of the perceived joints, by forward kinematics."""
        return self.ik.tcp_pose(np.asarray(joints, dtype=float))
