"""``SkillEnv``: what the generic core asks of a domain's env (``ArmEnv``, FrankaKitchen's
adapter, or a user's own), in full: the core types against it, never against ``ArmEnv``
(``tests/test_layers.py``), and a ``Domain`` checks every env it builds implements it
(``domain.spaces.check_env``).

Everything that decides (the executor, policies, classifier, fact detectors) reads only
``percept()`` and ``observe()``; ``facts()``, ``world_state()``, ``tcp_pose()`` and
``skill_success()`` are the simulator's truth, for scoring an episode, Algorithm 1's
scripted collection and set-ups (``tests/test_perception.py``: the executor runs a task on
an env whose truth accessors raise; ``tests/test_layers.py`` checks the source).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol, runtime_checkable

import gymnasium as gym
import numpy as np

from osg_control.domain.spec import Node, ObjectFrame, SkillSpec
from osg_control.perception.percept import Percept
from osg_control.perception.spec import PerceptionSpec


@runtime_checkable
class SkillEnv(Protocol):
    """A Gymnasium env with the paper's 10-D state and 7-D relative TCP action.

    Attributes:
        action_space: the 7-D action's box (``action_bounds`` either side).
        observation_space: the 10-D state's box.
        action_bounds: the per-step bound of each action component; its steps clip to
            them (the ``Domain``'s ``action_bounds``).
        perceptions: the perceptions (``perception.spec``) it simulates.
        perception: the perception it perceives with (its noise levels).
        nodes: the domain's nodes.
        home: the node a reset starts at without a skill or ``node`` option.
        skill: the skill whose reward and termination it gives, if any.
        anchor_offsets: truth (scoring, scripted collection): each object's displacement
            from its nominal place at the last reset.
    """

    @property
    def action_space(self) -> gym.spaces.Space[Any]: ...
    @property
    def observation_space(self) -> gym.spaces.Space[Any]: ...
    @property
    def action_bounds(self) -> np.ndarray: ...
    @property
    def perceptions(self) -> tuple[str, ...]: ...
    @property
    def perception(self) -> PerceptionSpec: ...
    @property
    def nodes(self) -> Mapping[str, Node]: ...
    @property
    def home(self) -> str: ...
    @property
    def skill(self) -> SkillSpec | None: ...
    @property
    def anchor_offsets(self) -> Mapping[str, np.ndarray]: ...

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

    def skill_success(
        self, skill: SkillSpec | None = None, world: np.ndarray | None = None
    ) -> bool:
        """Truth (scoring): a skill's success predicate on the simulator's state
        (``world``: its world-state vector, if the caller has read it already)."""
        ...

    def true_state(self) -> np.ndarray:
        """Truth (scoring): the simulator's 10-D state (TCP, gripper)."""
        ...

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Truth (scoring, set-ups): the TCP's position [m] and rotation matrix."""
        ...

    def world_state(self) -> np.ndarray:
        """Truth (scoring, labels): the world-state vector (the domain's ``world_fields``)."""
        ...

    def placement_world(
        self, placements: dict[str, np.ndarray], holding: str | None
    ) -> dict[str, Any]:
        """The ``world`` reset option that puts the domain's objects at ``placements``
        (``{}`` for a scene whose objects do not move, or those ``holding`` holds)."""
        ...


@runtime_checkable
class JointSpeedEnv(SkillEnv, Protocol):
    """A ``SkillEnv`` that drives a robot's joints and records their speeds (``ArmEnv``):
    what ``evaluation.joint_speeds`` measures.

    Attributes:
        peak_joint_speed_ratio: peak ``|joint velocity| / limit`` since the last reset.
        objects: the object frames nodes may be anchored to.
        world_sensors: world field -> what senses it.
    """

    @property
    def peak_joint_speed_ratio(self) -> float: ...
    @property
    def objects(self) -> tuple[ObjectFrame, ...]: ...
    @property
    def world_sensors(self) -> Mapping[str, str]: ...


MEMBERS: tuple[str, ...] = tuple(
    sorted({*SkillEnv.__annotations__, *(n for n in vars(SkillEnv) if not n.startswith("_"))})
)
"""The names ``SkillEnv`` asks for."""


def missing_members(env: Any) -> list[str]:
    """The ``SkillEnv`` members ``env`` lacks (none: it implements the contract)."""
    return [name for name in MEMBERS if not hasattr(env, name)]
