"""Diagnostic: would anchoring the valve's nodes carry the shipped valve skills to a moved
valve? An upper bound, with the valve's frame taken from the simulator's truth.

Each episode moves the valve (``world.valve_pos``) by a shift uniform in [-S, S] along x
and y, starts within 2 cm of ``above-valve`` moved with it, and runs the learned
``lower-to-valve``, ``push-valve-open`` and ``leave-valve`` in turn (each until its beta on
the percepts, its end node moved with the valve, or its step budget), their input the
observation in the valve's frame: the true shift (``anchored``) or none (the world frame,
as the executor ran them before the valve's place was a world field). It counts the
episodes that leave the valve open (truth). The oracle frame reads the truth: this is a
measurement of the skills, not a controller (``tools/displaced_cube.py --disturbance
moved-valve`` runs the executor from its percepts).

Usage: ``python tools/valve_oracle_frame.py [--episodes N] [--seed S] [--shift S]
[--perception NAME] [--models DIR] [--json]``.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from osg_control.domain.frames import in_skill_frame
from osg_control.domain.registry import get_domain
from osg_control.environment.success import success_holds
from osg_control.execution.executor import load_executor, task_env_config
from osg_control.kitchen.env import KitchenEnv
from osg_control.kitchen.valve import VALVE_HINGE, VALVE_SHIFT
from osg_control.kitchen.world import VALVE_OPEN_MIN
from osg_control.perception.spec import perception_spec

SKILLS = ("lower-to-valve", "push-valve-open", "leave-valve")
"""The valve skills run in turn from above the valve."""


def _episode(
    policies: dict, env: KitchenEnv, rng: np.random.Generator, shift: float, anchored: bool
) -> bool:
    kitchen = get_domain("kitchen")
    moved = np.array([*rng.uniform(-shift, shift, 2), 0.0])
    options = {
        "world": {"valve_pos": [VALVE_HINGE[0] + moved[0], VALVE_HINGE[1] + moved[1]]},
        "position": np.asarray(kitchen.nodes["above-valve"].position) + moved,
        "radius": 0.02,
        "gripper": "open",
    }
    obs, _ = env.reset(seed=int(rng.integers(2**31)), options=options)
    offset = moved if anchored else np.zeros(3)
    for name in SKILLS:
        skill = kitchen.skill(name)
        end = kitchen.nodes[skill.end]
        for _step in range(skill.max_steps):
            obs, *_ = env.step(policies[name](in_skill_frame(obs, offset)))
            seen = env.percept()
            goal = np.asarray(end.position) + offset
            if success_holds(skill, end, seen.state[:3], seen.state[7], seen.facts, goal):
                break
    return abs(env.world().valve_angle) >= VALVE_OPEN_MIN


def main() -> None:
    """Print the valve opened with the skills in the world frame and in the true frame."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=11)
    parser.add_argument("--shift", type=float, default=VALVE_SHIFT)
    parser.add_argument("--perception", default="robot")
    parser.add_argument("--models", default=None)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.episodes < 1:
        parser.error(f"--episodes must be at least 1, got {args.episodes}")
    if not 0.0 <= args.shift <= VALVE_SHIFT:
        parser.error(f"--shift must lie in [0, {VALVE_SHIFT}] m, got {args.shift}")
    executor = load_executor(get_domain("kitchen"), args.models, max_replans=0)
    env = KitchenEnv(config=task_env_config(perception_spec(args.perception)))
    opened = {
        frame: sum(
            _episode(
                executor.policies,
                env,
                np.random.default_rng([args.seed, i]),
                args.shift,
                frame == "anchored",
            )
            for i in range(args.episodes)
        )
        for frame in ("world", "anchored")
    }
    summary = {
        "episodes": args.episodes,
        "seed": args.seed,
        "shift": args.shift,
        "perception": args.perception,
        "opened": opened,
    }
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        for frame, count in opened.items():
            print(f"{frame} frame: valve opened {count}/{args.episodes}")


if __name__ == "__main__":
    main()
