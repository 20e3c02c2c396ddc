"""Peak simulated joint speed relative to the URDF limits over a skill's episodes.

The check behind ``tests/test_joint_speeds.py`` and ``tools/joint_speeds.py``: run a policy
from random starts, then the joint reset, and read the env's peak ``|qvel| / limit`` over
every physics substep (``ArmEnv.peak_joint_speed_ratio``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from osg_control.environment.arm_env import ArmEnv

START = {"radius": 0.05, "angle": 0.1}
"""Random starts within 5 cm and 0.1 rad of the skill's start node."""


def peak_joint_speed(
    env: ArmEnv, policy: Callable[[np.ndarray], np.ndarray], episodes: int
) -> float:
    """Largest ``|qvel| / limit`` over ``episodes`` runs of ``policy`` on ``env``'s skill
    (seeds 0, 1, ...) and the joint reset after each."""
    budget = env.skill.max_steps if env.skill else env.config.max_steps
    peak = 0.0
    for episode in range(episodes):
        obs, _ = env.reset(seed=episode, options=START)
        for _ in range(budget):
            obs, _reward, terminated, truncated, _info = env.step(policy(obs))
            if terminated or truncated:
                break
        env.joint_reset()
        peak = max(peak, env.peak_joint_speed_ratio)
    return peak
