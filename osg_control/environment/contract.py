"""``SkillEnv``: what the generic core asks of a domain's env (``ArmEnv``, FrankaKitchen's
adapter, or a user's own).

Everything that decides (the executor, policies, classifier, fact detectors) reads only
``percept()`` and ``observe()``; ``facts()``, ``world_state()``, ``tcp_pose()`` and
``skill_success()`` are the simulator's truth, for scoring an episode, Algorithm 1's
scripted collection and set-ups (``tests/test_perception.py``: the executor runs a task on
an env whose truth accessors raise; ``tests/test_layers.py`` checks the source).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

from osg_control.domain.spec import SkillSpec
from osg_control.perception.percept import Percept


@runtime_checkable
class SkillEnv(Protocol):
    """A Gymnasium env with the paper's 10-D state and 7-D relative TCP action."""

    @property
    def episode_over(self) -> bool:
        """A step since the last reset came back terminated or truncated."""
        ...

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """A start state (the domain's reset options)."""
        ...

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """One control step; the observation is the new percept's state."""
        ...

    def percept(self) -> Percept:
        """What the robot perceived at the last reset, step or joint reset."""
        ...

    def observe(self) -> np.ndarray:
        """The latest percept's 10-D state."""
        ...

    def joint_reset(self) -> int:
        """Bring the joints toward the home posture with the TCP held; the steps used."""
        ...

    def render(self) -> Any:
        """A frame of the scene (``render_mode="rgb_array"``), or None."""
        ...

    def facts(self) -> frozenset[str]:
        """Truth (scoring): the facts that hold in the simulator."""
        ...

    def true_state(self) -> np.ndarray:
        """Truth (scoring): the simulator's 10-D state (TCP, gripper)."""
        ...

    def world_state(self) -> np.ndarray:
        """Truth (scoring): the domain's world-state vector."""
        ...

    def skill_success(self, skill: SkillSpec | None = None) -> bool:
        """Truth (scoring): a skill's success predicate on the simulator's state."""
        ...
