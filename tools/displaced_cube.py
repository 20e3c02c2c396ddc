"""Recovery of a displaced object: a cube knocked 3-6 cm away right after the grasp, the
door left part open, or the valve moved (issue: objects anywhere).

Usage: ``python tools/displaced_cube.py [--disturbance knocked-cube|part-open-door|
moved-valve] [--episodes N] [--seed S] [--perception NAME] [--models DIR]
[--travel LOW HIGH] [--shift S] [--json]``.

- ``knocked-cube`` (default): each episode places the cube uniformly in its region, starts
  at home and runs ``cube-lifted``; once the cube has been held for a few steps it is
  teleported 3-6 cm away in a random direction onto the counter. An episode counts when
  the cube is lifted at the end (truth).
- ``part-open-door``: each episode slides the door to a travel uniform in ``--travel``
  (default 0.05-0.25 m; it counts as open from 0.30), as a slide that lost the handle
  leaves it, starts within 5 cm of ``door-front`` and runs ``door-open``; it reports the
  success (truth) and how many ``grab-handle`` runs held the handle.
- ``moved-valve``: each episode moves the valve (``world.valve_pos``) by a shift uniform
  in [-S, S] along x and y (``--shift``, default 0.04 m, the option's whole region; 0: the
  file's place), starts within 5 cm of ``home`` and runs ``turn-valve``'s goal; it reports
  the success (truth), also split by the larger of the two shifts (up to 2 cm, beyond).

The executor sees only its percepts (``kitchen.disturbances``).
"""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from osg_control.domain.registry import get_domain
from osg_control.execution.executor import load_executor, task_env_config
from osg_control.kitchen.disturbances import (
    knocked_cube_episode,
    moved_valve_episode,
    part_open_door_episode,
)
from osg_control.kitchen.valve import VALVE_SHIFT
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


def _moved_valve(executor: Any, env: Any, args: argparse.Namespace) -> dict[str, Any]:
    episodes = [
        moved_valve_episode(executor, env, np.random.default_rng([args.seed, i]), args.shift)
        for i in range(args.episodes)
    ]
    near = [e.opened for e in episodes if max(map(abs, e.shift)) <= 0.02]
    far = [e.opened for e in episodes if max(map(abs, e.shift)) > 0.02]
    return {
        "shift": args.shift,
        "success": sum(e.opened for e in episodes) / args.episodes,
        "opened_within_2cm": [sum(near), len(near)],
        "opened_beyond_2cm": [sum(far), len(far)],
        "mean_replans": float(np.mean([e.replans for e in episodes])),
    }


RUNS = {"knocked-cube": _knocked, "part-open-door": _part_open, "moved-valve": _moved_valve}


def main() -> None:
    """Print the recovery figures of the chosen disturbance."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--disturbance", choices=tuple(RUNS), default="knocked-cube")
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--perception", default="robot")
    parser.add_argument("--models", default=None)
    parser.add_argument("--travel", type=float, nargs=2, default=(0.05, 0.25))
    parser.add_argument("--shift", type=float, default=0.04)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.episodes < 1:
        parser.error(f"--episodes must be at least 1, got {args.episodes}")
    if not 0.0 <= args.travel[0] <= args.travel[1]:
        parser.error(f"--travel needs 0 <= LOW <= HIGH, got {args.travel}")
    if not 0.0 <= args.shift <= VALVE_SHIFT:
        parser.error(f"--shift must lie in [0, {VALVE_SHIFT}] m, got {args.shift}")
    kitchen = get_domain("kitchen")
    executor = load_executor(kitchen, args.models, max_replans=2)
    env = kitchen.make_env(config=task_env_config(perception_spec(args.perception)))
    run = RUNS[args.disturbance]
    summary = {
        "disturbance": args.disturbance,
        "episodes": args.episodes,
        "seed": args.seed,
        "perception": perception_spec(args.perception).to_dict(),
        **run(executor, env, args),
    }
    if args.json:
        print(json.dumps(summary, indent=2))
    elif args.disturbance == "moved-valve":
        print(
            f"valve opened {summary['success']:.2f} (within 2 cm "
            f"{summary['opened_within_2cm']}, beyond {summary['opened_beyond_2cm']})"
        )
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
