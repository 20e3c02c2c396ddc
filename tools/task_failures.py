"""Where a task's episodes fail: the skill that failed, its failure, and where the objects lay.

Usage: ``python tools/task_failures.py --task open-pick-up [--episodes N] [--seed S]
[--perception robot] [--noise SIGMA] [--filter [GAIN]] [--randomize-objects] [--replans 2]
[--models DIR] [--json]`` (the paper protocol: ``--perception paper --noise 0.02 --filter``).
Runs Tables IV/V's episodes (``evaluation.evaluate``: the same starts, regions and seeds as
``osg evaluate tasks``) one by one and, for each episode whose goal does not hold at the
end (truth), prints the start region, the objects' placements (truth, at the start), the
skills run with their outcome and the executor's failure. The last line counts failures
per failed skill and, per object, the mean placement of the failed against the succeeded
episodes. Diagnosis only: nothing here decides.
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from typing import Any

import numpy as np

from osg_control.commands import add_filter_argument
from osg_control.domain.registry import get_domain
from osg_control.evaluation.evaluate import (
    StartEpisode,
    _plain_env,
    _reset_in_region,
    cached_executor,
)
from osg_control.perception.spec import perception_spec


def _placements(env: Any, domain: Any) -> dict[str, list[float]]:
    world = env.read_world()
    index = {name: i for i, name in enumerate(domain.world_fields)}
    return {
        frame.name: [round(float(world[index[f]]), 4) for f in frame.position_fields]
        for frame in domain.objects
    }


def main() -> None:
    """Run the episodes and print every failure (``--json``: one object)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", required=True)
    parser.add_argument("--domain", default="kitchen")
    parser.add_argument("--episodes", type=int, default=10, help="episodes per start region")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--perception", default="robot")
    parser.add_argument(
        "--noise", type=float, default=0.0, help="the paper protocol's TCP noise [m] (default 0)"
    )
    add_filter_argument(parser)
    parser.add_argument("--randomize-objects", action="store_true")
    parser.add_argument("--replans", type=int, default=2)
    parser.add_argument("--models", default=None)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    domain = get_domain(args.domain)
    task = domain.task(args.task)
    domain = domain.for_task(task)  # the scene of its objects (e.g. two cubes)
    perception = perception_spec(args.perception, args.noise)
    executor = cached_executor(domain.ref, args.models, args.replans, args.filter)
    env = _plain_env(domain.ref, perception)
    failures: list[dict[str, Any]] = []
    placed: dict[bool, list[dict[str, list[float]]]] = {True: [], False: []}
    for region in range(len(domain.start_regions)):
        for i in range(args.episodes):
            start = StartEpisode(
                domain.ref,
                task.name,
                args.models,
                region,
                perception,
                args.seed,
                region,
                i,
                args.randomize_objects,
            )
            obs = _reset_in_region(env, start, domain.task_world(task))
            where = _placements(env, domain)
            result = executor.execute(task.goal, env, obs)
            success = set(task.goal) <= env.facts()
            placed[success].append(where)
            if not success:
                failed = [o for o in result.outcomes if not o.success]
                failures.append(
                    {
                        "region": domain.start_regions[region].name,
                        "index": i,
                        "placements": where,
                        "skills": [(o.skill, o.success, o.failure) for o in result.outcomes],
                        "failed_skills": [o.skill for o in failed],
                        "failure": result.failure,
                        "final_facts": sorted(env.facts()),
                    }
                )
                if not args.json:
                    print(json.dumps(failures[-1]))
    total = args.episodes * len(domain.start_regions)
    by_skill = Counter(s for f in failures for s in dict.fromkeys(f["failed_skills"]))
    means = {
        key: {
            name: np.mean([p[name] for p in placed[key]], axis=0).round(4).tolist()
            for name in (placed[key][0] if placed[key] else {})
        }
        for key in (True, False)
    }
    summary = {
        "task": task.name,
        "episodes": total,
        "seed": args.seed,
        "perception": perception.to_dict(),
        "filter_gain": args.filter,
        "success": 1.0 - len(failures) / total,
        "failed_skills": dict(by_skill),
        "mean_placement_failed": means[False],
        "mean_placement_succeeded": means[True],
    }
    if args.json:
        print(json.dumps({**summary, "failures": failures}, indent=2))
    else:
        print(json.dumps(summary))


if __name__ == "__main__":
    main()
