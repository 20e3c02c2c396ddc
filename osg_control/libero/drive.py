"""Our differential IK driving LIBERO's arm through robosuite's ``JOINT_POSITION``
controller: each step, the IK's next joint target from the observed joint positions becomes
the controller's joint delta.

The IK's joint speeds are capped so one step's delta never exceeds what the controller
takes (``env.JOINT_DELTA_LIMIT``, the Panda's speed limits over a step) on a leg in free
space (``transit``), and ``CAREFUL_DELTA`` on the others (near contact, and the learned
pick, whose data were recorded at that pace): the QP, not a clip afterwards, keeps the
motion's direction.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.control.description import RobotDescription
from osg_control.control.ik import DiffIKController
from osg_control.control.ik_backends import IKConfig
from osg_control.control.ik_tasks import IKState, VelocityLimit
from osg_control.libero.env import JOINT_DELTA_LIMIT

JOINTS_OBS = "robot0_joint_pos"
TCP_OBS = "robot0_eef_pos"
GRIPPER_OPEN, GRIPPER_CLOSED = -1.0, 1.0
"""robosuite's gripper commands."""
CAREFUL_DELTA = 0.05
"""The largest joint delta of a step [rad] on a leg near contact: robosuite's default
``output_max``, the pace every contact leg was written and measured at (docs/libero.md:
at the transit pace a finger landed on a mug's rim and a book tipped, LIBERO-10 tasks 4
and 5)."""
REACH_STEP = 0.05
"""How far ahead of the TCP the IK is told to go in one step on a transit leg [m]
(``TURN_STEP`` the same for the turn): told the whole error at once, the joints at their
caps bought the step with the motion's direction (the hand turning in place drifted 17 cm
and swept into a mug, and an approach arrived fast and carried 1.5 cm past its hover into
the descent, LIBERO-10 task 4 state 1)."""
TURN_STEP = 0.15
"""How far ahead of the hand's rotation the IK is told to turn in one step on a transit
leg [rad]."""


REACH_CHECK_STEPS = 150
"""IK steps a reach check iterates from the present joints (``JointTargetDriver.reaches``;
the hand crosses the table in a few dozen at the arm's full pace)."""
REACH_TOLERANCE = 0.01
"""How near the IK must bring the TCP for a point to count as reached [m] (a place's
descent ends this near)."""


class PacedLimit(VelocityLimit):
    """``|dq| <= pace v_max dt``: the joint speed limits scaled by ``pace`` in (0, 1], set
    before each solve."""

    def __init__(self, velocity: np.ndarray, dt: float) -> None:
        super().__init__(velocity, dt)
        self.pace = 1.0

    def box(self, state: IKState) -> tuple[np.ndarray, np.ndarray]:
        low, high = super().box(state)
        return self.pace * low, self.pace * high


class JointTargetDriver:
    """TCP targets -> LIBERO ``JOINT_POSITION`` actions (7 scaled joint deltas + gripper).

    Args:
        robot: the arm where the scene stands it (``robot.mounted_panda``).
        config: the IK's weights and backend; its ``dt`` must be the env's control period
            and its ``velocity_scale`` is set from ``JOINT_DELTA_LIMIT``.
    """

    def __init__(self, robot: RobotDescription, config: IKConfig | None = None) -> None:
        base = config or IKConfig(dt=1.0 / robot.control_hz)
        fastest = base.dt * max(robot.arm.velocity)
        scale = min(1.0, JOINT_DELTA_LIMIT / fastest)
        self._limit = PacedLimit(np.array(robot.arm.velocity) * scale, base.dt)
        self._careful = min(1.0, CAREFUL_DELTA / (fastest * scale))
        self.ik = DiffIKController(robot, replace(base, velocity_scale=scale), limits=[self._limit])

    def action(
        self,
        joints: np.ndarray,
        target_pos: np.ndarray,
        target_rot: np.ndarray,
        gripper: float = GRIPPER_OPEN,
        transit: bool = False,
    ) -> np.ndarray:
        """The action that moves the TCP toward ``target_pos`` and ``target_rot`` (world
        frame) from the perceived joints (``robot0_joint_pos``), with the gripper command:
        on a leg in free space (``transit``) at the arm's full pace, the IK told at most a
        step's reach and turn ahead (``REACH_STEP``, ``TURN_STEP``); else joint deltas of at
        most ``CAREFUL_DELTA``, the IK told the whole error (a push presses with it)."""
        q = np.asarray(joints, dtype=float)
        self._limit.pace = 1.0 if transit else self._careful
        if transit:
            target_pos, target_rot = self._ahead(q, target_pos, target_rot)
        delta = self.ik.step(q, target_pos, target_rot) - q
        return np.r_[np.clip(delta / JOINT_DELTA_LIMIT, -1.0, 1.0), gripper]

    def _ahead(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The target cut to ``REACH_STEP`` and ``TURN_STEP`` ahead of the TCP."""
        here, now = self.ik.tcp_pose(q)
        turn = Rotation.from_matrix(now.T @ target_rot).as_rotvec()
        angle = float(np.linalg.norm(turn))
        if angle > TURN_STEP:
            target_rot = now @ Rotation.from_rotvec(turn * TURN_STEP / angle).as_matrix()
        reach = np.asarray(target_pos, dtype=float) - here
        distance = float(np.linalg.norm(reach))
        if distance > REACH_STEP:
            target_pos = here + reach * REACH_STEP / distance
        return target_pos, target_rot

    def settle(
        self, joints: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray, steps: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """The TCP pose the IK ends at, iterated ``steps`` times from ``joints`` toward the
        target at the arm's full pace with nothing in the way: as near as the arm gets to
        it from there (no controller, no contacts)."""
        self._limit.pace = 1.0
        q = np.asarray(joints, dtype=float)
        for _ in range(steps):
            q = self.ik.step(q, target_pos, target_rot)
        return self.ik.tcp_pose(q)

    def reaches(
        self, joints: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray,
        turn_tolerance: float,
    ) -> bool:  # fmt: skip
        """Whether the IK, iterated ``REACH_CHECK_STEPS`` times from ``joints``
        (``settle``), ends within ``REACH_TOLERANCE`` and ``turn_tolerance`` [rad] of the
        target: whether the arm gets there from here."""
        pos, rot = self.settle(joints, target_pos, target_rot, REACH_CHECK_STEPS)
        turn = Rotation.from_matrix(rot.T @ np.asarray(target_rot)).magnitude()
        return bool(np.linalg.norm(pos - target_pos) <= REACH_TOLERANCE and turn <= turn_tolerance)

    def tcp_pose(self, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The TCP pose (position, rotation) of the perceived joints, by forward kinematics."""
        return self.ik.tcp_pose(np.asarray(joints, dtype=float))
