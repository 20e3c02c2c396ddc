"""The skill env's step, kept once for every plant: check the action, latch the gripper,
turn the action into the plant's command (the env's IK), let the plant's ``Actuation`` run
one control step, count it, score it on the truth (``EpisodeState.step_outcome``), perceive,
and report. ``ArmEnv`` drives its own MuJoCo scene (``stepping.MujocoActuation``); a domain's
adapter drives an outside env through that env's own ``step`` (e.g.
``franka.actuation.KitchenStepActuation``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import mujoco
import numpy as np

from osg_control.control.divergence import non_finite_state
from osg_control.environment.actions import latched_gripper
from osg_control.environment.episode import EpisodeState
from osg_control.environment.truth import TruthReadouts
from osg_control.perception.percept import Percept

StepResult = tuple[np.ndarray, float, bool, bool, dict[str, Any]]
"""What ``step`` returns: Gymnasium's (observation, reward, terminated, truncated, info)."""


@dataclass
class Actuated:
    """What one control step of a plant gave.

    Attributes:
        failure: why the physics diverged, else None.
        reward, terminated, truncated: an outside env's own (its reward is the step's
            reward only without a skill).
        info: the plant's own step info (e.g. ``joint_speed_ratio``, ``env_reward``).
    """

    failure: str | None = None
    reward: float = 0.0
    terminated: bool = False
    truncated: bool = False
    info: dict[str, Any] = field(default_factory=dict)


class Actuation(Protocol):
    """How a command reaches a plant: one control step each ``apply``."""

    def apply(self, command: np.ndarray, gripper_cmd: float) -> Actuated:
        """Run one control step toward ``command`` (the env's IK output) with the latched
        gripper command."""
        ...

    def halt(self, failure: str) -> Actuated:
        """A step not run: the joint state was non-finite (``failure`` names it)."""
        ...


class SkillStepper(EpisodeState, TruthReadouts):
    """The step part of a skill env (``SkillEnv``): the env sets ``data``, ``actuation``
    and ``_gripper_cmd`` and implements the hooks below; the step is scored and reported
    on its truth (``TruthReadouts``)."""

    data: mujoco.MjData
    actuation: Actuation
    _gripper_cmd: float

    def step(self, action: np.ndarray) -> StepResult:
        """One control step with a 7-D relative TCP action. A non-finite joint position
        (set from outside since the last step) ends the episode as a divergence:
        ``terminated``, ``info["failure"]`` naming the joint, nothing sent to the actuators
        (a non-finite velocity MuJoCo reports itself, as ``BADQVEL``).

        Raises:
            ValueError: a malformed action (``check_action``).
        """
        action = self.check_action(action)
        if non_finite_state(self.data, ("qpos",)) is None:
            self._gripper_cmd = latched_gripper(self._gripper_cmd, action[6])
            return self.advance(self._command(action), action)
        return self.advance(None, action)

    def advance(self, command: np.ndarray | None, applied: np.ndarray) -> StepResult:
        """Run the plant one control step toward ``command`` (None: the joint state is
        non-finite, nothing run) and report it as a step of the episode (``applied``: the
        action reported in ``info["action_applied"]``)."""
        failure = non_finite_state(self.data, ("qpos",)) if command is None else None
        if failure is not None:
            actuated = self.actuation.halt(failure)
        else:
            assert command is not None  # a finite state always comes with a command
            actuated = self.actuation.apply(command, self._gripper_cmd)
            failure = actuated.failure
        self._steps += 1
        world = self._true_world()
        facts = self.facts_of(world)
        skill = self.skill
        reward, terminated, truncated = self.step_outcome(
            failure,
            lambda: skill is not None and self._truth_success(skill, facts),
            self._step_budget(),
            actuated.terminated,
            actuated.truncated,
        )
        if skill is None:
            reward = float(actuated.reward)  # without a skill, the plant's own reward
        info = self._info(world, facts)
        info["percept"] = self._step_percept(world, facts)
        info.update(actuated.info)
        info.update(self._sensor_info())
        info["action_applied"] = applied
        if failure is not None:
            info["failure"] = failure
        return self.observe(), reward, bool(terminated), bool(truncated), info

    # ----------------------------------------------------------------- the env's hooks
    def _command(self, action: np.ndarray) -> np.ndarray:
        """The plant's command for a checked action, from the perceived state (the IK)."""
        raise NotImplementedError

    def _step_budget(self) -> int | None:
        """The steps after which a step is truncated (None: no budget of the env's own)."""
        raise NotImplementedError

    def _step_percept(self, world: np.ndarray, facts: frozenset[str]) -> Percept:
        """Perceive after a step (``world``/``facts``: the truth, already read)."""
        raise NotImplementedError

    def _sensor_info(self) -> dict[str, Any]:
        """Info the sensors add after the percept (e.g. the cameras' report)."""
        return {}
