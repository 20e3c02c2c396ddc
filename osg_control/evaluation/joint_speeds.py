"""Peak simulated joint speed relative to the URDF limits over a skill's episodes.

The check behind ``tests/test_joint_speeds.py`` and ``tools/joint_speeds.py``: run a policy
from random starts, then the joint reset, and read the env's peak ``|qvel| / limit`` over
every physics substep (``ArmEnv.peak_joint_speed_ratio``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from osg_control.environment.arm_env import ArmEnv

START = {"radius": 0.05, "angle": 0.1}
"""Random starts within 5 cm and 0.1 rad of the skill's start node."""


@dataclass(frozen=True)
class SpeedCheck:
    """The outcome of ``peak_joint_speed``."""

    peak_ratio: float
    """Largest ``|qvel| / limit`` over every substep of every episode and joint reset."""
    successes: int
    """Episodes in which the skill succeeded."""


def peak_joint_speed(
    env: ArmEnv, policy: Callable[[np.ndarray], np.ndarray], episodes: int
) -> SpeedCheck:
    """Run ``policy`` on ``env``'s skill for ``episodes`` episodes (seeds 0, 1, ...), each
    followed by the joint reset; the peak speed ratio and the successes.

    Raises:
        ValueError: ``env`` was made without a skill.
    """
    if env.skill is None:
        raise ValueError("peak_joint_speed needs an env made with skill=...")
    budget = env.skill.max_steps
    peak, successes = 0.0, 0
    for episode in range(episodes):
        obs, _ = env.reset(seed=episode, options=START)
        for _ in range(budget):
            obs, _reward, terminated, truncated, info = env.step(policy(obs))
            if terminated or truncated:
                break
        successes += bool(info["success"])
        env.joint_reset()
        peak = max(peak, env.peak_joint_speed_ratio)
    return SpeedCheck(peak, successes)
