"""Peak simulated joint speed relative to the URDF limits over shipped-policy episodes.

Usage: ``python tools/joint_speeds.py [--episodes N] [--skill NAME ...] [--unlimited]``.
Runs each shipped kitchen policy from random starts (then the joint reset) and prints the
largest |qvel| / limit over every physics substep and the successes, then the same peak
under full-speed TCP commands along each axis from home (``evaluation.joint_speeds``);
``--unlimited`` turns the speed limit off (``EnvConfig(limit_joint_speed=False)``).
"""

from __future__ import annotations

import argparse

from osg_control.domain.registry import get_domain
from osg_control.environment.arm_env import EnvConfig
from osg_control.evaluation.joint_speeds import DIRECTIONS, full_speed_peak, peak_joint_speed
from osg_control.execution.defaults import load_defaults


def main() -> None:
    """Print the peak ratio per skill and per full-speed direction."""
    kitchen = get_domain("kitchen")
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=3)
    parser.add_argument("--skill", nargs="*", default=[s.name for s in kitchen.skills])
    parser.add_argument("--unlimited", action="store_true")
    args = parser.parse_args()
    policies = load_defaults(kitchen).policies
    config = EnvConfig(limit_joint_speed=not args.unlimited)
    for name in args.skill:
        env = kitchen.make_env(skill=kitchen.skill(name), config=config)
        check = peak_joint_speed(env, policies[name], args.episodes)
        print(
            f"{name:26s} peak |qvel|/limit {check.peak_ratio:.3f}  "
            f"successes {check.successes}/{args.episodes}"
        )
    for direction in DIRECTIONS:
        peak = full_speed_peak(kitchen.make_env(config=config), direction)
        print(f"full speed {direction:15s} peak |qvel|/limit {peak:.3f}")


if __name__ == "__main__":
    main()
