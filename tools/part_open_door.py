"""Open-door from a door left part open, as a slide that lost the handle leaves it.

Usage: ``python tools/part_open_door.py [--episodes N] [--seed S] [--low L] [--high H]
[--perception NAME] [--models DIR] [--json]``. Each episode slides the door to a travel
drawn uniformly in [low, high] m (shut: 0; it counts as open from 0.30), starts the arm
within 5 cm of ``door-front`` with the hand empty and runs the executor (<= 2 replans) to
``door-open``. It reports the task's success (truth) and how many ``grab-handle`` runs held
the handle: a grab that heads for where the handle was (the shut door's) times out.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from osg_control.domain.registry import get_domain
from osg_control.execution.executor import load_executor, task_env_config
from osg_control.perception.spec import perception_spec


def main() -> None:
    """Run the episodes and print the success rate and the grabs that held."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--low", type=float, default=0.05)
    parser.add_argument("--high", type=float, default=0.25)
    parser.add_argument("--perception", default="robot")
    parser.add_argument("--models", default=None)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if not 0.0 <= args.low <= args.high:
        parser.error(f"need 0 <= --low <= --high, got {args.low} and {args.high}")
    kitchen = get_domain("kitchen")
    executor = load_executor(kitchen, args.models, max_replans=2)
    env = kitchen.make_env(config=task_env_config(perception_spec(args.perception)))
    start = {"position": kitchen.nodes["door-front"].position, "radius": 0.05}
    successes, grabs, held = 0, 0, 0
    for i in range(args.episodes):
        rng = np.random.default_rng([args.seed, i])
        travel = float(rng.uniform(args.low, args.high))
        options = {**start, "gripper": "open", "world": {"door_opening": travel}}
        obs, _ = env.reset(seed=int(rng.integers(2**31)), options=options)
        result = executor.execute(["door-open"], env, obs)
        successes += "door-open" in env.facts()  # truth: scoring only
        runs = [o for o in result.outcomes if o.skill == "grab-handle"]
        grabs += len(runs)
        held += sum(o.success for o in runs)
    summary = {
        "episodes": args.episodes,
        "seed": args.seed,
        "travel": [args.low, args.high],
        "perception": args.perception,
        "success": successes / args.episodes,
        "grab_handle_runs": grabs,
        "grab_handle_held": held,
    }
    print(json.dumps(summary, indent=2) if args.json else summary)


if __name__ == "__main__":
    main()
