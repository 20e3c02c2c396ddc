"""``JointReset``: an arm's joints driven toward its home posture with the TCP held.

Null-space motion: the TCP pose is an equality constraint of the IK QP and the posture task
pulls toward ``IKConfig.posture`` (the robot's home by default). An arm without a null space
(six joints or fewer, ``RobotDescription.redundant``) cannot move with its TCP held: the
reset logs so once and takes no step. Decided from the encoders alone, as a robot's
controller would: the joints are read every step, the TCP is held where forward kinematics
of the joints read at the start puts it.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import mujoco
import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.control.divergence import non_finite_state
from osg_control.control.ik import DiffIKController, IKConfig, joint_reset_controller
from osg_control.errors import SimulationError

_LOG = logging.getLogger(__name__)


class JointReset:
    """The joint reset of one env's arm (its reset IK built on first use).

    Args:
        robot: the arm.
        ik: the env's IK configuration (the reset's controller is built from it).
    """

    def __init__(self, robot: RobotDescription, ik: IKConfig) -> None:
        self.robot = robot
        self.ik = ik
        self._controller: DiffIKController | None = None
        self._said_no_null_space = False

    def run(
        self,
        data: mujoco.MjData,
        encoders: Callable[[], np.ndarray],
        posture: np.ndarray,
        simulate: Callable[[np.ndarray], str | None],
        max_steps: int,
        tolerance: float,
    ) -> int:
        """Drive the joints toward ``posture`` until every joint is within ``tolerance``
        [rad] of it or the posture error stops shrinking; the control steps used.

        Args:
            data: the simulation (checked for a non-finite joint state every step).
            encoders: reads the arm's joints as the robot perceives them.
            posture: the target posture [rad].
            simulate: runs one control step toward joint targets; a failure reason or None.

        Raises:
            SimulationError: the physics diverged (or the joint state is non-finite).
        """
        if not self.robot.redundant:
            if not self._said_no_null_space:
                _LOG.info(
                    "joint reset skipped: robot %r has %d joints, no null space under its TCP task",
                    self.robot.name,
                    self.robot.n_joints,
                )
                self._said_no_null_space = True
            return 0
        if self._controller is None:
            self._controller = joint_reset_controller(self.robot, self.ik)
        controller = self._controller
        held: tuple[np.ndarray, np.ndarray] | None = None  # the TCP pose to hold

        def step(joints: np.ndarray) -> bool:
            nonlocal held
            diverged = non_finite_state(data, ("qpos",))
            if diverged is None:
                held = held or controller.tcp_pose(joints)
                diverged = simulate(controller.reset_step(joints, *held))
            if diverged is not None:
                raise SimulationError(f"{diverged} during joint reset")
            return False

        return drive_to_posture(encoders, posture, step, max_steps, tolerance)


def drive_to_posture(
    joints: Callable[[], np.ndarray],
    posture: np.ndarray,
    step: Callable[[np.ndarray], bool],
    max_steps: int,
    tolerance: float,
) -> int:
    """The joint reset's loop, every env's: read the perceived ``joints``; stop when every
    joint is within ``tolerance`` [rad] of ``posture`` or the error stopped shrinking (by
    1e-4 rad); else run one control ``step`` from the joints read (True: the episode
    ended, stop). The control steps used.

    Raises:
        SimulationError: from ``step``, the physics diverged.
    """
    current = joints()
    previous = np.inf
    for count in range(max_steps):
        error = float(np.abs(current - posture).max())
        if error < tolerance or error > previous - 1e-4:
            return count
        previous = error
        if step(current):
            return count + 1
        current = joints()
    return max_steps
