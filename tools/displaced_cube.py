"""Recovery of a displaced object: a cube knocked 3-6 cm away right after the grasp, or the
door left part open (issue: objects anywhere).

Usage: ``python tools/displaced_cube.py [--disturbance knocked-cube|part-open-door]
[--episodes N] [--seed S] [--perception NAME] [--models DIR] [--travel LOW HIGH] [--json]``.

- ``knocked-cube`` (default): each episode places the cube uniformly in its region, starts
  at home and runs ``cube-lifted``; once the cube has been held for a few steps it is
  teleported 3-6 cm away in a random direction onto the counter. An episode counts when
  the cube is lifted at the end (truth).
- ``part-open-door``: each episode slides the door to a travel uniform in ``--travel``
  (default 0.05-0.25 m; it counts as open from 0.30), as a slide that lost the handle
  leaves it, starts within 5 cm of ``door-front`` and runs ``door-open``; it reports the
  success (truth) and how many ``grab-handle`` runs held the handle.

The executor sees only its percepts (``kitchen.disturbances``).
"""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from osg_control.domain.registry import get_domain
from osg_control.execution.executor import load_executor, task_env_config
from osg_control.kitchen.disturbances import knocked_cube_episode, part_open_door_episode
from osg_control.perception.spec import perception_spec


def _knocked(executor: Any, env: Any, args: argparse.Namespace) -> dict[str, Any]:
    episodes = [
        knocked_cube_episode(executor, env, np.random.default_rng([args.seed, i]))
        for i in range(args.episodes)
    ]
    knocked = sum(e.knocked for e in episodes)
    recovered = sum(e.recovered for e in episodes)
    return {
        "knocked": knocked,
        "recovered_episodes": recovered,
        "recovered": recovered / max(knocked, 1),
        "mean_replans": float(np.mean([e.replans for e in episodes if e.knocked] or [0])),
    }


def _part_open(executor: Any, env: Any, args: argparse.Namespace) -> dict[str, Any]:
    low, high = args.travel
    episodes = [
        part_open_door_episode(executor, env, np.random.default_rng([args.seed, i]), low, high)
        for i in range(args.episodes)
    ]
    return {
        "travel": [low, high],
        "success": sum(e.opened for e in episodes) / args.episodes,
        "grab_handle_runs": sum(e.grabs for e in episodes),
        "grab_handle_held": sum(e.grabs_held for e in episodes),
    }


def main() -> None:
    """Print the recovery figures of the chosen disturbance."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--disturbance", choices=("knocked-cube", "part-open-door"), default="knocked-cube"
    )
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--perception", default="robot")
    parser.add_argument("--models", default=None)
    parser.add_argument("--travel", type=float, nargs=2, default=(0.05, 0.25))
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.episodes < 1:
        parser.error(f"--episodes must be at least 1, got {args.episodes}")
    if not 0.0 <= args.travel[0] <= args.travel[1]:
        parser.error(f"--travel needs 0 <= LOW <= HIGH, got {args.travel}")
    kitchen = get_domain("kitchen")
    executor = load_executor(kitchen, args.models, max_replans=2)
    env = kitchen.make_env(config=task_env_config(perception_spec(args.perception)))
    run = _knocked if args.disturbance == "knocked-cube" else _part_open
    summary = {
        "disturbance": args.disturbance,
        "episodes": args.episodes,
        "seed": args.seed,
        "perception": perception_spec(args.perception).to_dict(),
        **run(executor, env, args),
    }
    if args.json:
        print(json.dumps(summary, indent=2))
    elif args.disturbance == "knocked-cube":
        print(
            f"recovered {summary['recovered_episodes']}/{summary['knocked']} knocked"
            f" ({summary['recovered']:.2f}), mean replans {summary['mean_replans']:.2f}"
        )
    else:
        print(
            f"door opened {summary['success']:.2f}; grab-handle held "
            f"{summary['grab_handle_held']}/{summary['grab_handle_runs']}"
        )


if __name__ == "__main__":
    main()
