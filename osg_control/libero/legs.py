"""The leg runner and the motion primitives every operator controller is built from: a
leg moves the TCP to a target recomputed from the current percept each step, with a
gripper command, until it is near (or a condition holds, or its steps run out). The
``Context`` is what the controllers of one episode share.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.control.description import RobotDescription
from osg_control.libero.drive import JointTargetDriver
from osg_control.libero.operators import PLACES
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.problem import Atom, LiberoProblem
from osg_control.libero.scene import Scene

Target = Callable[[LiberoPercept, LiberoPercept], tuple[np.ndarray, np.ndarray | None]]
"""(percept now, percept when the leg started) -> TCP position and rotation (None: the
controller's grasp rotation)."""
TURN_TOLERANCE = 0.1
"""A leg that names a rotation is reached only within this of it [rad]."""
HOVER = 0.10
"""Height above a thing's grasp point the empty hand approaches [m]."""
CREEP_TOLERANCE = 0.002
"""How near the top of its rise a creeping leg (``creep``) ends [m]."""
STALL_STEPS = 8
"""Steps a transit leg may go without getting nearer its unchanged target (by ``PROGRESS``
or ``TURN_PROGRESS``) before it counts as stalled and ends (``StallWatch``)."""
PROGRESS, TURN_PROGRESS = 0.001, 0.01
"""How much nearer its target position [m] or rotation [rad] than ever before a transit
leg must get over ``STALL_STEPS`` steps; a target that moves more than this in a step is
a new one."""
GraspRule = Callable[[LiberoPercept], tuple[np.ndarray, np.ndarray]]
"""percept -> the TCP point and rotation an object is grasped at (``Context.grasps``)."""


Step = tuple[str, tuple[str, ...]]
"""One ground operator of a plan: its name and arguments."""


def first_places(steps: list[Step]) -> list[tuple[str, str, str]]:
    """Each object's first place in a plan's ``steps`` (``place-in`` / ``place-on``), in
    order, as (operator, object, target): an object is grasped for where it goes next."""
    places: dict[str, tuple[str, str, str]] = {}
    for operator, args in steps:
        if operator in PLACES and args[0] not in places:
            places[args[0]] = (operator, args[0], args[1])
    return list(places.values())


class Runner(Protocol):
    """Runs one operator: ``act`` gives the next action, or None when it is done."""

    def act(self, percept: LiberoPercept) -> np.ndarray | None:
        """The next JOINT_POSITION action, or None when the operator is done."""
        ...


@dataclass(frozen=True)
class Leg:
    """One leg: move the TCP to a target with a gripper command until within
    ``tolerance`` (0: for all ``steps``), or until ``until`` holds, or ``steps`` run out;
    at the arm's full pace in free space (``transit``), else at the careful pace of a leg
    near contact (``drive.JointTargetDriver.action``). A transit leg also ends when it
    stalls (``LegRunner``)."""

    target: Target
    gripper: float
    steps: int
    tolerance: float = 0.01
    until: Callable[[LiberoPercept], bool] | None = None
    transit: bool = False


@dataclass
class Context:
    """What every controller of an episode shares: the scene, the IK driver, the top-down
    rotation of the episode's start (``base``, which fixture controllers use), the last
    commanded rotation (``rotation``: a leg that names none keeps it), the home height,
    the objects' categories, where the arm's base stands (``base_xy``), the distance
    between the open fingers (``open_span``, from the robot's gripper), the grasps
    chosen and failed so far, and those that replace the top-down one for objects the
    plan takes somewhere it does not fit (``grasps``: set by the plan executor from what
    the plan does next, ``insert``), the drawers the plan approaches to open next
    (``opening``: the approach turns the hand for the pull, ``fixtures.drawer_hand``), the
    objects the plan lets go lying into a region (``tipped``: another lands on them,
    ``tip``), and the task's goal atoms (``goal``: a place leaves room for what the goal still puts
    beside it)."""

    scene: Scene
    driver: JointTargetDriver
    base: np.ndarray
    home_z: float
    categories: dict[str, str]
    base_xy: np.ndarray
    open_span: float
    grasps: dict[str, GraspRule] = field(default_factory=dict)
    goal: tuple[Atom, ...] = ()
    opening: frozenset[str] = frozenset()
    tipped: frozenset[str] = frozenset()

    def __post_init__(self) -> None:
        self.rotation = self.base
        self.failures: dict[str, int] = {}
        """Failed picks per object so far (the executor counts them; a retry grasps
        otherwise: ``grasp.chosen_grip``)."""
        self.grips: dict[str, Any] = {}
        """The grasp chosen per object, with the attempt and where it was (``grasp``)."""
        self.reach_checks: dict[str, tuple[int, np.ndarray, dict[tuple[float, ...], bool]]] = {}
        """Per object, the attempt and where it was when its grasps' reach was checked, and
        the checks (``grasp``)."""
        self.drawered: dict[str, tuple[np.ndarray, bool]] = {}
        """Per object, where it was when last seen to move and whether it has been
        perceived in a drawer since (``grasp``)."""

    @classmethod
    def at_start(
        cls, scene: Scene, driver: JointTargetDriver, robot: RobotDescription,
        percept: LiberoPercept, problem: LiberoProblem,
    ) -> Context:  # fmt: skip
        """An episode's context from its first percept: the hand's rotation and height
        there, the problem's objects and goal, the arm's base where ``robot`` is mounted."""
        return cls(scene, driver, driver.tcp_pose(percept.joints)[1], float(percept.tcp[2]),
                   dict(problem.objects), np.r_[robot.mount[0][:2], 0.0],
                   robot.gripper.max_opening, goal=problem.goal)  # fmt: skip


class StallWatch:
    """Whether a leg stalled: over its last ``STALL_STEPS`` percepts the TCP got no nearer
    its target position by ``PROGRESS`` and the hand no nearer its target rotation by
    ``TURN_PROGRESS`` than at any percept before them since the target last moved (a
    target that moves starts the watch anew: the hand turning toward one of two grasps
    alike, then toward the other, is not stalled; nor is a hand turning in place)."""

    def __init__(self) -> None:
        self.target: tuple[np.ndarray, np.ndarray] | None = None
        self.errors: list[tuple[float, float]] = []

    def stalled(self, pos: np.ndarray, rot: np.ndarray, tcp: np.ndarray, hand: np.ndarray) -> bool:
        """Watch one more percept (the TCP at ``tcp``, the hand's rotation ``hand``) of a
        leg aiming at ``pos`` and ``rot``; whether it has stalled."""
        if self.target is not None and (
            np.linalg.norm(pos - self.target[0]) > PROGRESS
            or _angle(rot, self.target[1]) > TURN_PROGRESS
        ):
            self.errors = []
        self.target = (np.asarray(pos, dtype=float), rot)
        self.errors.append((float(np.linalg.norm(tcp - pos)), _angle(hand, rot)))
        if len(self.errors) <= STALL_STEPS:
            return False
        errors = np.array(self.errors)
        gained = errors[:-STALL_STEPS].min(axis=0) - errors[-STALL_STEPS:].min(axis=0)
        return bool(gained[0] < PROGRESS and gained[1] < TURN_PROGRESS)


def yawed(angle: float) -> np.ndarray:
    """The rotation by ``angle`` [rad] about the vertical."""
    return Rotation.from_rotvec([0.0, 0.0, angle]).as_matrix()


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """The angle between two rotations [rad]."""
    return float(Rotation.from_matrix(a.T @ b).magnitude())


class LegRunner:
    """Runs legs in order; ``act`` returns the next action, or None when all are done.

    A transit leg also ends when it stalls (``StallWatch``): its IK then got as near as it
    can, and waiting out its steps would leave the arm where it is. A bowl 0.8 m out lies
    5 mm beyond the top-down hand's reach (LIBERO-Spatial task 6): the approach stopped
    9 mm short of its 8 mm tolerance, or rocked about the stretched elbow 17 mm short, and
    waited out its 90 steps (the episode its 220)."""

    def __init__(self, legs: list[Leg], context: Context) -> None:
        self.legs, self.context = legs, context
        self.index, self.steps = 0, 0
        self.start: LiberoPercept | None = None
        self.watch = StallWatch()

    def act(self, percept: LiberoPercept) -> np.ndarray | None:
        """The next JOINT_POSITION action, or None when the last leg is done."""
        command = self.command(percept)
        if command is None:
            return None
        pos, rot, gripper = command
        transit = self.legs[self.index].transit
        return self.context.driver.action(percept.joints, pos, rot, gripper, transit)

    def command(self, percept: LiberoPercept) -> tuple[np.ndarray, np.ndarray, float] | None:
        """The next TCP target (position, rotation) and gripper command, or None when the
        last leg is done (``act`` drives it; a recorder perturbs it first)."""
        while self.index < len(self.legs):
            leg = self.legs[self.index]
            if self.start is None:
                self.start, self.watch = percept, StallWatch()
            pos, rot = leg.target(percept, self.start)
            _, now = self.context.driver.tcp_pose(percept.joints)
            near = leg.tolerance > 0 and bool(np.linalg.norm(percept.tcp - pos) < leg.tolerance)
            if near and rot is not None:  # a leg that turns the hand also waits for the turn
                near = _angle(now, rot) < TURN_TOLERANCE
            aim = self.context.rotation if rot is None else rot  # the rotation commanded
            stalled = leg.transit and self.watch.stalled(pos, aim, percept.tcp, now)
            stop = (leg.until is not None and leg.until(percept)) or stalled
            if not (near or stop) and self.steps < leg.steps:
                self.steps += 1
                if rot is not None:
                    self.context.rotation = rot
                return pos, self.context.rotation, leg.gripper
            self.index, self.steps, self.start = self.index + 1, 0, None
        return None


def here(offset: tuple[float, float, float]) -> Target:
    """The point ``offset`` from where the TCP was when the leg started; no rotation."""
    return lambda now, start: (start.tcp + offset, None)


def hold(gripper: float, steps: int) -> Leg:
    """Stay where the leg starts, commanding the gripper, for ``steps``."""
    return Leg(here((0.0, 0.0, 0.0)), gripper, steps, 0.0)


def up(height: float, gripper: float, until: Callable[[LiberoPercept], bool] | None = None) -> Leg:
    """Straight up ``height`` from where the leg starts, commanding the gripper (ending
    where it is once ``until`` holds)."""
    return Leg(here((0.0, 0.0, height)), gripper, 30, 0.02, until)


def creep(height: float, rate: float, gripper: float, steps: int) -> Leg:
    """Straight up ``height`` from where the leg starts, the target never more than
    ``rate`` above the TCP: the IK, told a small error, moves the arm slowly (it is told
    the whole error on a careful leg, ``drive.JointTargetDriver.action``)."""

    def target(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        top = start.tcp[2] + height
        return np.r_[start.tcp[:2], min(now.tcp[2] + rate, top)], None

    return Leg(target, gripper, steps, CREEP_TOLERANCE)
