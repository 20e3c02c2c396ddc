"""Peak simulated joint speed relative to the URDF limits over a skill's episodes.

The checks behind ``tests/test_joint_speeds.py`` and ``tools/joint_speeds.py``: run a policy
from random starts, then the joint reset, or full-speed TCP commands along an axis (the
hardest case for the servo), and read the env's peak ``|qvel| / limit`` over every physics
substep (``ArmEnv.peak_joint_speed_ratio``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from osg_control.domain.contract import JointSpeedEnv
from osg_control.domain.frames import in_skill_frame, offsets_of

START = {"radius": 0.05, "angle": 0.1}
"""Random starts within 5 cm and 0.1 rad of the skill's start node."""
FULL_SPEED_STEPS = 40
"""Control steps of a full-speed probe (2 s: the arm reaches and holds its top speed)."""
DIRECTIONS = ("+x", "-x", "+y", "-y", "+z", "-z")


@dataclass(frozen=True)
class SpeedCheck:
    """The outcome of ``peak_joint_speed``."""

    peak_ratio: float
    """Largest ``|qvel| / limit`` over every substep of every episode and joint reset."""
    successes: int
    """Episodes in which the skill succeeded."""


def peak_joint_speed(
    env: JointSpeedEnv, policy: Callable[[np.ndarray], np.ndarray], episodes: int
) -> SpeedCheck:
    """Run ``policy`` on ``env``'s skill for ``episodes`` episodes (seeds 0, 1, ...), each
    followed by the joint reset; the peak speed ratio and the successes.

    Raises:
        ValueError: ``env`` was made without a skill.
    """
    if env.skill is None:
        raise ValueError("peak_joint_speed needs an env made with skill=...")
    budget = env.skill.max_steps
    anchor = env.nodes[env.skill.end].anchor
    peak, successes = 0.0, 0
    for episode in range(episodes):
        obs, _ = env.reset(seed=episode, options=START)
        for _ in range(budget):
            obs, _reward, terminated, truncated, info = env.step(
                policy(_skill_frame(env, anchor, obs))
            )
            if terminated or truncated:
                break
        successes += bool(info["success"])
        env.joint_reset()
        peak = max(peak, env.peak_joint_speed_ratio)
    return SpeedCheck(peak, successes)


def _skill_frame(env: JointSpeedEnv, anchor: str | None, obs: np.ndarray) -> np.ndarray:
    """The observation in the skill's frame: relative to its object as perceived."""
    if anchor is None:
        return obs
    offsets = offsets_of(env.objects, tuple(env.world_sensors), env.percept().world)
    return in_skill_frame(obs, offsets[anchor])


def full_speed_peak(env: JointSpeedEnv, direction: str, steps: int = FULL_SPEED_STEPS) -> float:
    """The peak ``|qvel| / limit`` under ``steps`` TCP commands at the action bound along
    ``direction`` (one of ``DIRECTIONS``) from the env's home node (seed 0).

    Raises:
        ValueError: an unknown direction.
    """
    if direction not in DIRECTIONS:
        raise ValueError(f"unknown direction {direction!r}; known directions: {DIRECTIONS}")
    axis = "xyz".index(direction[1])
    action = np.zeros(7)
    action[axis] = env.action_bounds[axis] * (1.0 if direction[0] == "+" else -1.0)
    env.reset(seed=0, options={"node": env.home})
    for _ in range(steps):
        env.step(action)
    return env.peak_joint_speed_ratio
