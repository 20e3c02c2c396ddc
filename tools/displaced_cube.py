"""Recovery of a cube knocked 3-6 cm away right after the grasp (issue: objects anywhere).

Usage: ``python tools/displaced_cube.py [--episodes N] [--seed S] [--perception NAME]
[--models DIR] [--json]``. Each episode places the cube uniformly in its region, starts at
home and runs ``cube-lifted``; once the cube has been held for a few steps it is teleported
3-6 cm away in a random direction onto the counter (``kitchen.disturbances``). The executor
sees only its percepts; an episode counts when the cube is lifted at the end (truth).
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from osg_control.domain.registry import get_domain
from osg_control.execution.executor import load_executor, task_env_config
from osg_control.kitchen.disturbances import knocked_cube_episode
from osg_control.perception.spec import perception_spec


def main() -> None:
    """Print the recovery rate over the episodes whose cube was knocked (and the replans)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--perception", default="robot")
    parser.add_argument("--models", default=None)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    kitchen = get_domain("kitchen")
    executor = load_executor(kitchen, args.models, max_replans=2)
    env = kitchen.make_env(config=task_env_config(perception_spec(args.perception)))
    episodes = [
        knocked_cube_episode(executor, env, np.random.default_rng([args.seed, i]))
        for i in range(args.episodes)
    ]
    knocked = sum(e.knocked for e in episodes)
    recovered = sum(e.recovered for e in episodes)
    summary = {
        "episodes": args.episodes,
        "seed": args.seed,
        "perception": perception_spec(args.perception).to_dict(),
        "knocked": knocked,
        "recovered": recovered / max(knocked, 1),
        "mean_replans": float(np.mean([e.replans for e in episodes if e.knocked] or [0])),
    }
    print(
        json.dumps(summary, indent=2)
        if args.json
        else f"recovered {recovered}/{knocked} knocked ({summary['recovered']:.2f}), "
        f"mean replans {summary['mean_replans']:.2f}"
    )


if __name__ == "__main__":
    main()
