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
GraspRule = Callable[[LiberoPercept], tuple[np.ndarray, np.ndarray]]
"""percept -> the TCP point and rotation an object is grasped at (``Context.grasps``)."""


Step = tuple[str, tuple[str, ...]]
"""One ground operator of a plan: its name and arguments."""


def first_places(steps: list[Step]) -> list[tuple[str, str, str]]:
    """Each object's first place in a plan's ``steps`` (``place-in`` / ``place-on``), in
    order, as (operator, object, target): an object is grasped for where it goes next."""
    places: dict[str, tuple[str, str, str]] = {}
    for operator, args in steps:
        if operator in ("place-in", "place-on") and args[0] not in places:
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
    near contact (``drive.JointTargetDriver.action``)."""

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
    the objects' categories, where the arm's base stands (``base_xy``), the grasps
    chosen and failed so far, and those that replace the top-down one for objects the
    plan takes somewhere it does not fit (``grasps``: set by the plan executor from what
    the plan does next, ``insert``), the drawers the plan approaches to open next
    (``opening``: the approach turns the hand for the pull, ``fixtures.drawer_hand``), and
    the task's goal atoms (``goal``: a place leaves room for what the goal still puts
    beside it)."""

    scene: Scene
    driver: JointTargetDriver
    base: np.ndarray
    home_z: float
    categories: dict[str, str]
    base_xy: np.ndarray
    grasps: dict[str, GraspRule] = field(default_factory=dict)
    goal: tuple[Atom, ...] = ()
    opening: frozenset[str] = frozenset()

    def __post_init__(self) -> None:
        self.rotation = self.base
        self.failures: dict[str, int] = {}
        """Failed picks per object so far (the executor counts them; a retry grasps
        otherwise: ``grasp.chosen_grip``)."""
        self.grips: dict[str, Any] = {}
        """The grasp chosen per object, with the attempt and where it was (``grasp``)."""

    @classmethod
    def at_start(
        cls, scene: Scene, driver: JointTargetDriver, robot: RobotDescription,
        percept: LiberoPercept, problem: LiberoProblem,
    ) -> Context:  # fmt: skip
        """An episode's context from its first percept: the hand's rotation and height
        there, the problem's objects and goal, the arm's base where ``robot`` is mounted."""
        return cls(scene, driver, driver.tcp_pose(percept.joints)[1], float(percept.tcp[2]),
                   dict(problem.objects), np.r_[robot.mount[0][:2], 0.0],
                   goal=problem.goal)  # fmt: skip


class LegRunner:
    """Runs legs in order; ``act`` returns the next action, or None when all are done."""

    def __init__(self, legs: list[Leg], context: Context) -> None:
        self.legs, self.context = legs, context
        self.index, self.steps = 0, 0
        self.start: LiberoPercept | None = None

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
                self.start = percept
            pos, rot = leg.target(percept, self.start)
            near = leg.tolerance > 0 and np.linalg.norm(percept.tcp - pos) < leg.tolerance
            if near and rot is not None:  # a leg that turns the hand also waits for the turn
                _, now = self.context.driver.tcp_pose(percept.joints)
                near = Rotation.from_matrix(now.T @ rot).magnitude() < TURN_TOLERANCE
            stop = leg.until is not None and leg.until(percept)
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


def up(height: float, gripper: float) -> Leg:
    """Straight up ``height`` from where the leg starts, commanding the gripper."""
    return Leg(here((0.0, 0.0, height)), gripper, 30, 0.02)
