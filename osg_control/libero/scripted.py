"""A scripted pick-and-place controller from observed object poses, driven by our IK: the
oracle data collector for Algorithm 1 in LIBERO's scenes (not the skill graph: it is told
the task file's goal and scripts every motion; its success is not a policy's result).

For each goal atom ``(in OBJ REGION)`` or ``(on OBJ TARGET)`` whose target is a movable
object (its pose in the observation: a basket's region, a plate), in the file's order:
above the object, down, close, lift, above the target, down, open, up. Every waypoint is
read from the observation when the phase starts. A goal it cannot script (a fixture's
region or joint: drawers, stove, microwave) makes it hold still: it declines rather than
guesses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.libero.drive import GRIPPER_CLOSED, GRIPPER_OPEN, TCP_OBS, JointTargetDriver
from osg_control.libero.problem import Atom, LiberoProblem

SCRIPTABLE = ("in", "on")
"""Goal predicates it scripts (placing a movable object)."""


@dataclass(frozen=True)
class Phase:
    """One leg: where the TCP goes relative to the object or target, with the gripper."""

    relative_to: str  # "object", "target", or "here" (the TCP when the leg starts)
    offset: tuple[float, float, float]
    gripper: float
    steps: int  # the most steps the leg may take
    tolerance: float = 0.01  # [m]; 0: run all its steps (closing, opening)


PHASES = (
    Phase("object", (0.0, 0.0, 0.10), GRIPPER_OPEN, 60, 0.02),
    Phase("object", (0.0, 0.0, 0.005), GRIPPER_OPEN, 40, 0.008),
    Phase("here", (0.0, 0.0, 0.0), GRIPPER_CLOSED, 12, 0.0),
    Phase("here", (0.0, 0.0, 0.25), GRIPPER_CLOSED, 40, 0.03),
    Phase("target", (0.0, 0.0, 0.30), GRIPPER_CLOSED, 80, 0.02),
    Phase("target", (0.0, 0.0, 0.18), GRIPPER_CLOSED, 30, 0.02),
    Phase("here", (0.0, 0.0, 0.0), GRIPPER_OPEN, 10, 0.0),
    Phase("here", (0.0, 0.0, 0.08), GRIPPER_OPEN, 20, 0.02),
)
"""One atom's legs [m]: the grasp 5 mm above the object's origin (2 cm higher missed the
flat boxes: cream cheese, butter, pudding); carried 30 cm above the target's origin so a
hanging bottle clears a basket's rim (at 20 cm it pushed the basket); released 18 cm above.
Step caps fit two legs of free motion into LIBERO-Object's 280 steps."""


class ScriptedPickPlace:
    """The scripted oracle (see the module docstring); a ``benchmark.LiberoPolicy``."""

    name = "scripted-oracle"

    def start(
        self, problem: LiberoProblem, robot: RobotDescription, obs: dict[str, np.ndarray]
    ) -> None:
        """Plan the goal's scriptable atoms; hold still if any atom is not scriptable."""
        self.problem = problem
        self.driver = JointTargetDriver(robot)
        self.rotation = self.driver.tcp_pose(obs)[1]  # keep the start's top-down grasp
        self.atoms = [a for a in problem.goal if self._scriptable(a, obs)]
        self.declined = len(self.atoms) < len(problem.goal)
        self.atom, self.phase, self.steps = 0, 0, 0
        self.leg: np.ndarray | None = None

    def _target_body(self, atom: Atom) -> str:
        target = atom.args[1]
        region = self.problem.regions.get(target)
        return region.parent if region is not None else target

    def _scriptable(self, atom: Atom, obs: dict[str, np.ndarray]) -> bool:
        return (
            atom.predicate in SCRIPTABLE
            and f"{atom.args[0]}_pos" in obs
            and f"{self._target_body(atom)}_pos" in obs
        )

    def _leg_target(self, phase: Phase, atom: Atom, obs: dict[str, np.ndarray]) -> np.ndarray:
        origin = {
            "object": lambda: obs[f"{atom.args[0]}_pos"],
            "target": lambda: obs[f"{self._target_body(atom)}_pos"],
            "here": lambda: obs[TCP_OBS],
        }[phase.relative_to]()
        return np.asarray(origin, dtype=float) + phase.offset

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """The next JOINT_POSITION action (held still once done or when declined)."""
        while not self.declined and self.atom < len(self.atoms):
            atom, phase = self.atoms[self.atom], PHASES[self.phase]
            if self.leg is None:
                self.leg = self._leg_target(phase, atom, obs)
            reached = phase.tolerance > 0 and np.linalg.norm(obs[TCP_OBS] - self.leg) < (
                phase.tolerance
            )
            if not reached and self.steps < phase.steps:
                self.steps += 1
                return self.driver.action(obs, self.leg, self.rotation, phase.gripper)
            self.leg, self.steps, self.phase = None, 0, self.phase + 1
            if self.phase == len(PHASES):
                self.atom, self.phase = self.atom + 1, 0
        return np.r_[np.zeros(7), GRIPPER_OPEN]
