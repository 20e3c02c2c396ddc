"""Goal-aware entry against the classifier's argmax: task success and skills executed.

Usage: ``python tools/entry_choice.py [--episodes N] [--task T ...] [--noise S] [--filter G]
[--perception NAME] [--seed S] [--json]``. The same starts as Tables IV/V (the domain's
start regions, ``evaluation.evaluate``'s seeds), ≤ 2 replans, each episode run twice: with
``Executor(goal_aware_entry=True)`` (the default) and ``False`` (the paper's executor);
scored on the simulator's truth. One process.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from osg_control.domain.registry import get_domain
from osg_control.evaluation.evaluate import StartEpisode, _plain_env, _reset_in_region
from osg_control.execution.executor import load_executor
from osg_control.perception.spec import perception_spec


def main() -> None:
    """Print success and mean skills executed per task, for both entry rules."""
    kitchen = get_domain("kitchen")
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=10, help="per start region")
    parser.add_argument("--task", nargs="+", default=[t.name for t in kitchen.tasks])
    parser.add_argument("--noise", type=float, default=0.02)
    parser.add_argument("--filter", type=float, default=0.2)
    parser.add_argument("--perception", default="paper")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    noise = args.noise if args.perception == "paper" else 0.0
    spec = perception_spec(args.perception, noise)
    rows = {}
    for aware in (True, False):
        for name in args.task:
            task = kitchen.task(name)
            scene = kitchen.for_task(task)  # the kitchen with the task's cubes
            env = _plain_env(scene.ref, spec)
            executor = load_executor(
                scene, max_replans=2, filter_gain=args.filter, goal_aware_entry=aware
            )
            successes, skills = [], []
            for region in range(len(kitchen.start_regions)):
                for index in range(args.episodes):
                    start = StartEpisode(scene.ref, name, None, region, spec, args.seed,
                                         region, index)  # fmt: skip
                    obs = _reset_in_region(env, start, scene.task_world(task))
                    result = executor.execute(task.goal, env, obs)
                    successes.append(set(task.goal) <= env.facts())
                    skills.append(len(result.outcomes))
            rows.setdefault(name, {})["goal-aware" if aware else "argmax"] = {
                "success": float(np.mean(successes)),
                "skills_executed": float(np.mean(skills)),
            }
    summary = {"episodes_per_task": args.episodes * len(kitchen.start_regions),
               "perception": spec.to_dict(), "filter_gain": args.filter, "tasks": rows}  # fmt: skip
    if args.json:
        print(json.dumps(summary, indent=2))
        return
    for name, row in rows.items():
        aware, argmax = row["goal-aware"], row["argmax"]
        print(
            f"{name:22s} goal-aware {aware['success']:.3f} ({aware['skills_executed']:.2f} "
            f"skills)  argmax {argmax['success']:.3f} ({argmax['skills_executed']:.2f} skills)"
        )


if __name__ == "__main__":
    main()
