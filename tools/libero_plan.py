"""Plan every LIBERO task file's goal over the lifted domain osg-libero, per suite.

For each task of each ``--suite`` (default: all 16), plans with each of ``--planners``
(wall time of grounding plus search, ``libero.plan.plan_task``) and reports per suite:
tasks planned, plan lengths (min / median / max steps), the median and maximum planning
time per planner, and whether every planner returned the same cost. Needs the ``libero``
extra (run it in that environment); deterministic (no randomness).

    python tools/libero_plan.py [--suite libero_10 ...] [--planners astar-hmax astar
        fast-downward] [--json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from typing import Any

from osg_control.libero.plan import plan_task
from osg_control.libero.suites import suite_names
from osg_control.libero.tasks import task_count, task_problem


def plan_suite(suite: str, planners: list[str]) -> dict[str, Any]:
    """Plan each task of ``suite`` with each planner: one row per task, and the summary."""
    rows = []
    for index in range(task_count(suite)):
        problem = task_problem(suite, index)
        row: dict[str, Any] = {"task": index, "name": problem.name, "planners": {}}
        for planner in planners:
            started = time.perf_counter()
            result = plan_task(problem, planner)
            row["planners"][planner] = {
                "status": result.status,
                "cost": result.cost,
                "steps": None if result.steps is None else len(result.steps),
                "time_s": time.perf_counter() - started,
                "expanded": result.stats.expanded,
            }
        rows.append(row)
    first = planners[0]
    lengths = [n for r in rows if (n := r["planners"][first]["steps"]) is not None]
    return {
        "suite": suite,
        "tasks": len(rows),
        "planned": {p: sum(r["planners"][p]["status"] == "solved" for r in rows) for p in planners},
        "same_cost": all(len({r["planners"][p]["cost"] for p in planners}) == 1 for r in rows),
        "steps": [min(lengths), statistics.median(lengths), max(lengths)] if lengths else None,
        "time_s": {
            p: {
                "median": statistics.median(r["planners"][p]["time_s"] for r in rows),
                "max": max(r["planners"][p]["time_s"] for r in rows),
            }
            for p in planners
        },
        "rows": rows,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", nargs="+", default=list(suite_names()), choices=suite_names())
    parser.add_argument("--planners", nargs="+", default=["astar-hmax", "astar", "fast-downward"])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    summaries = [plan_suite(suite, args.planners) for suite in args.suite]
    if args.json:
        print(json.dumps(summaries, indent=1))
        return
    for s in summaries:
        planned = " ".join(f"{p} {n}/{s['tasks']}" for p, n in s["planned"].items())
        times = " ".join(
            f"{p} {1000 * t['median']:.0f}/{1000 * t['max']:.0f} ms" for p, t in s["time_s"].items()
        )
        print(f"{s['suite']:<22} planned: {planned}; steps min/median/max {s['steps']}; "
              f"same cost: {s['same_cost']}; time median/max: {times}")  # fmt: skip


if __name__ == "__main__":
    main()
