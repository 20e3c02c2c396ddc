"""Peak simulated joint speed relative to the URDF limits over shipped-policy episodes.

Usage: ``python tools/joint_speeds.py [--episodes N] [--skill NAME ...]``. Records |qvel| of
the arm after every physics substep (skills and joint resets) and prints, per skill, the
largest ratio to the velocity limit.
"""

from __future__ import annotations

import argparse

import mujoco
import numpy as np

from osg_control.control.ik import urdf_velocity_limits
from osg_control.domain.registry import get_domain
from osg_control.execution.defaults import load_defaults
from osg_control.kitchen.env import KitchenEnv
from osg_control.kitchen.skills import SKILLS

KITCHEN = get_domain("kitchen")


def peak_speed_ratio(skill: str, episodes: int, policies: dict) -> float:
    """Largest |qvel| / limit over every substep of ``episodes`` runs of ``skill``."""
    env = KitchenEnv(skill=skill)
    limits = urdf_velocity_limits()
    peak = 0.0
    recording = False  # the start's settling in reset is not commanded motion
    step = mujoco.mj_step

    def recording_step(model: mujoco.MjModel, data: mujoco.MjData) -> None:
        nonlocal peak
        step(model, data)
        if recording:
            peak = max(peak, float(np.max(np.abs(data.qvel[env._arm_dof]) / limits)))

    mujoco.mj_step = recording_step
    try:
        for episode in range(episodes):
            recording = False
            obs, _ = env.reset(seed=episode, options={"radius": 0.05, "angle": 0.1})
            recording = True
            for _ in range(env.skill.max_steps if env.skill else 100):
                obs, _r, terminated, truncated, _info = env.step(policies[skill](obs))
                if terminated or truncated:
                    break
            env.joint_reset()
    finally:
        mujoco.mj_step = step
    return peak


def main() -> None:
    """Print the peak ratio per skill."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--episodes", type=int, default=3)
    parser.add_argument("--skill", nargs="*", default=[s.name for s in SKILLS])
    args = parser.parse_args()
    _loaded = load_defaults(KITCHEN)
    policies, _ = _loaded.policies, _loaded.classifier
    for name in args.skill:
        print(f"{name:26s} peak |qvel|/limit {peak_speed_ratio(name, args.episodes, policies):.3f}")


if __name__ == "__main__":
    main()
