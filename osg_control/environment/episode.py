"""``EpisodeState``: what every skill env keeps of its episode, whatever drives its arm
(``ArmEnv``'s own MuJoCo scene, or an outside env such as FrankaKitchen-v1 behind a domain's
adapter): the latest percept and its state, whether the episode is over, the action's
check against the domain's bounds, and a step's outcome (the skill's sparse reward, the
termination and the step budget). Part of the ``domain.contract.SkillEnv`` contract, kept
once here."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from osg_control.domain.spec import SkillSpec
from osg_control.environment.actions import checked_action
from osg_control.perception.percept import Percept


class EpisodeState:
    """The episode part of a skill env (the env's ``__init__`` and ``reset`` set the
    attributes below; ``step`` keeps them)."""

    action_bounds: np.ndarray
    skill: SkillSpec | None
    _percept: Percept | None
    _episode_over: bool
    _succeeded: bool
    _steps: int

    def percept(self) -> Percept:
        """What the robot perceived at the last reset, step or joint reset: the only input
        of whatever decides (the executor, policies, classifier, fact detectors)."""
        if self._percept is None:
            raise RuntimeError("the env has not been reset")
        return self._percept

    def observe(self) -> np.ndarray:
        """The perceived 10-D state of the latest percept (a copy)."""
        return self.percept().state.copy()

    @property
    def episode_over(self) -> bool:
        """Whether a step since the last reset came back terminated or truncated: the
        episode is over and, by Gymnasium's protocol, takes no more steps."""
        return self._episode_over

    def check_action(self, action: np.ndarray) -> np.ndarray:
        """Validate an action (real numbers, shape (7,), finite) and clip it to
        ``action_bounds``.

        Raises:
            ValueError: wrong shape or NaN/inf; nothing reaches the actuators.
        """
        return checked_action(action, self.action_bounds)

    def step_outcome(
        self,
        failure: str | None,
        succeeds: Callable[[], bool],
        budget: int | None,
        terminated: bool = False,
        truncated: bool = False,
    ) -> tuple[float, bool, bool]:
        """A step's reward, ``terminated`` and ``truncated``, after ``_steps`` was counted.

        With a skill, its sparse reward: 1 on the step its success first holds
        (``succeeds``, asked only then), which terminates the episode. A ``failure`` (the
        physics diverged) terminates it. It is truncated at ``budget`` steps unless it
        terminated. ``terminated`` and ``truncated`` carry an outside env's own.

        Returns:
            (reward, terminated, truncated); the reward is 0 without a skill.
        """
        reward = 0.0
        if failure is None and self.skill is not None and not self._succeeded and succeeds():
            self._succeeded = True
            reward = 1.0
        terminated = terminated or reward == 1.0 or failure is not None
        truncated = truncated or (not terminated and budget is not None and self._steps >= budget)
        self._episode_over = self._episode_over or terminated or truncated
        return reward, terminated, truncated
