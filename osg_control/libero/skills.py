"""The ``skills`` policy: the plan executor (``executor.PlanExecutor``) in which the
operators a learned skill runs (``pick`` and ``pick-out``: ``recording.OPERATORS``) run
its network, every other operator its scripted controller.

A learned skill decides each step from the lifted observation (``features.observe``) and
its action becomes a TCP target for ``drive.JointTargetDriver`` (``features.command``). It
ends when its effect is perceived (``pick_place.holding_ok``) or its step budget
(``recording.SKILL_MAX_STEPS``) is spent; the executor then checks the effect as for a
scripted operator (and lets go, lifts and replans on a failure). A rule closes the gripper
when the network's descent stalls over the grasp point (``stall_close``: the scripted
pick's close there, which the network did not learn).
"""

from __future__ import annotations

from functools import partial
from pathlib import Path

import numpy as np

from osg_control.errors import CheckpointError
from osg_control.learning.checkpoints import check_action_scale, checkpoint_paths
from osg_control.learning.policy import SkillPolicy
from osg_control.libero.benchmark import PolicyFactory
from osg_control.libero.executor import PlanExecutor
from osg_control.libero.facts import held
from osg_control.libero.features import (
    ACTION_DIM,
    ACTION_SCALE,
    OBS_DIM,
    GripperMemory,
    command,
    observe,
)
from osg_control.libero.legs import Context, Leg, Runner
from osg_control.libero.operators import SCHEMAS
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.pick_place import DESCENT_TOLERANCE, holding_ok
from osg_control.libero.recording import OPERATORS, SKILL_MAX_STEPS
from osg_control.libero.stall_close import StallClose
from osg_control.libero.training import DEFAULTS_DIR, MANIFEST, SKILLS_DIR, read_manifest

POLICY = "skills"


def load_skills(directory: Path) -> dict[str, SkillPolicy]:
    """The learned skills of a skills folder (``training``'s layout), each checked.

    Raises:
        CheckpointError: the folder, its manifest or a checkpoint is missing or corrupt,
            or a checkpoint's sizes or action scale are not the lifted ones (named).
    """
    if not directory.is_dir():
        raise CheckpointError(f"{directory}: LIBERO skills folder not found")
    manifest = read_manifest(directory)
    policies = {}
    for name in manifest["skills"]:
        policy = SkillPolicy.load(directory / SKILLS_DIR, name, OBS_DIM, ACTION_DIM)
        sidecar = checkpoint_paths(directory / SKILLS_DIR, name)[1]
        check_action_scale(sidecar, policy.checkpoint.action_scale, ACTION_SCALE.tolist())
        policies[name] = policy
    return policies


def shipped() -> bool:
    """Whether the package ships learned LIBERO skills (``training.DEFAULTS_DIR``)."""
    return (DEFAULTS_DIR / MANIFEST).is_file()


def learned_operators(names: list[str]) -> tuple[list[str], list[str]]:
    """The operators of ``osg-libero`` the skills ``names`` run, and the scripted rest."""
    learned = [op for name in names for op in OPERATORS[name]]
    return learned, [s.name for s in SCHEMAS if s.name not in learned]


class LearnedRunner:
    """Runs one learned skill on one object (a ``legs.Runner``)."""

    def __init__(
        self, ctx: Context, policy: SkillPolicy, obj: str, start_z: float, trace: list[str]
    ) -> None:
        self.ctx, self.policy, self.obj, self.start_z = ctx, policy, obj, start_z
        self.trace, self.steps, self.gripper = trace, 0, GripperMemory()
        self.stall = StallClose(DESCENT_TOLERANCE)

    def act(self, percept: LiberoPercept) -> np.ndarray | None:
        """The network's next action as a JOINT_POSITION action; None when the effect is
        perceived, the budget is spent, the stalled close missed or the network gave no
        finite action (traced)."""
        if self.steps >= SKILL_MAX_STEPS or (
            self.steps and holding_ok(self.ctx, percept, self.obj, self.start_z)
        ):
            return None
        if self.stall.missed(held(self.ctx.scene, percept, self.obj)):
            self.trace.append(f"learned {self.policy.skill.name}: the stalled close missed")
            return None
        try:
            obs = observe(self.ctx, percept, self.obj, self.start_z, self.gripper)
            position, rotation, gripper = command(self.ctx, percept, self.policy(obs))
        except ValueError as err:
            self.trace.append(f"learned {self.policy.skill.name}: stopped ({err})")
            return None
        closed = self.stall.closed
        gripper = self.stall.gripper(obs[:3], gripper)
        if self.stall.closed and not closed:
            self.trace.append(f"learned {self.policy.skill.name}: closed on a stalled descent")
        action = self.ctx.driver.action(percept.joints, position, rotation, gripper)
        if not np.all(np.isfinite(action)):
            self.trace.append(f"learned {self.policy.skill.name}: non-finite joint action")
            return None
        self.steps += 1
        self.ctx.rotation = rotation
        self.gripper.given(gripper)
        return action


class SkillsExecutor(PlanExecutor):
    """The ``skills`` policy (see the module docstring)."""

    name = POLICY

    def __init__(self, policies: dict[str, SkillPolicy], planner: str = "auto") -> None:
        super().__init__(planner)
        self.by_operator = {op: p for name, p in policies.items() for op in OPERATORS[name]}

    def _learned(self, operator: str) -> bool:
        return operator in self.by_operator

    def _runner(self, operator: str, args: tuple[str, ...], legs: list[Leg]) -> Runner:
        policy = self.by_operator.get(operator)
        if policy is None:
            return super()._runner(operator, args, legs)
        return LearnedRunner(self.ctx, policy, args[0], self.start_z, self.trace)


def skills_policy(directory: str) -> SkillsExecutor:
    """The ``skills`` policy of a skills folder (a module-level factory for workers)."""
    return SkillsExecutor(load_skills(Path(directory)))


def skills_factory(directory: Path) -> PolicyFactory:
    """A picklable factory of ``skills_policy(directory)`` (checked here first)."""
    load_skills(directory)
    return partial(skills_policy, str(directory))
