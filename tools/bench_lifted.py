"""Benchmark planning over N objects of one type with a domain's lifted skills.

Builds a synthetic problem of ``--count`` instances of ``--type`` (default: the kitchen,
cubes) from the domain's lifted PDDL domain (measured costs of its shipped defaults) and a
goal that every instance satisfies (``--goal-predicate``, default ``in-cabinet``), plus
``--extra-goal`` atoms, from its start world with the instances' ``--init-predicate``
atoms (default ``on-counter``). Reports, per built-in planner (median of ``--repeats``):
the grounding (the ground task: operators kept), the search, and their sum against the
100 ms target as a ratio; with Fast Downward installed, its cost on the same files.

    python tools/bench_lifted.py [--domain kitchen] [--type cube] [--count 3] [--repeats 5]
        [--extra-goal "(door-open door-1)"] [--json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from osg_control.domain.registry import get_domain
from osg_control.execution.bundle import measured_graph
from osg_control.planning.api import graph_domain, solve
from osg_control.planning.fast_downward import find_fast_downward
from osg_control.planning.grounding import ground
from osg_control.planning.pddl_io import build_problem, write_pddl
from osg_control.planning.synthetic import with_instances

TARGET_S = 0.1
"""The issue's target for planning a 3-cube problem with the built-in planner."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--domain", default="kitchen")
    parser.add_argument("--type", default="cube")
    parser.add_argument("--count", type=int, default=3)
    parser.add_argument("--goal-predicate", default="in-cabinet")
    parser.add_argument("--init-predicate", default="on-counter")
    parser.add_argument("--extra-goal", default="(door-open door-1)")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--planners", nargs="+", default=["auto", "astar-hmax", "astar", "ucs"])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    base = get_domain(args.domain)
    domain = with_instances(base, args.type, args.count)
    objects = domain.lifting.of_type(args.type)
    pddl = graph_domain(domain, measured_graph(base))
    world = [*base.start_world, *(f"({args.init_predicate} {o})" for o in objects)]
    goal = " ".join([args.extra_goal, *(f"({args.goal_predicate} {o})" for o in objects)])
    problem = build_problem(pddl, base.home, world, goal, name=f"{args.type}-x{args.count}")
    rows = []
    for planner in args.planners:
        grounding, searches, result = [], [], None
        for _ in range(args.repeats):
            started = time.perf_counter()
            task = ground(pddl.domain, problem)
            grounding.append(time.perf_counter() - started)
            started = time.perf_counter()
            result = solve(pddl.domain, problem, planner)
            searches.append(time.perf_counter() - started - grounding[-1])
        assert result is not None
        total = statistics.median(grounding) + statistics.median(searches)
        rows.append(
            {
                "planner": planner,
                "status": result.status,
                "cost": result.cost,
                "steps": len(result.actions),
                "ground_operators": len(task.operators),
                "grounding_ms": round(statistics.median(grounding) * 1000, 2),
                "search_ms": round(statistics.median(searches) * 1000, 2),
                "total_ms": round(total * 1000, 2),
                "ratio_to_target": round(total / TARGET_S, 3),
            }
        )
    fd_cost = None
    if find_fast_downward() is not None:
        with tempfile.TemporaryDirectory() as tmp:
            files = (
                write_pddl(pddl.domain, Path(tmp) / "domain.pddl"),
                write_pddl(problem, Path(tmp) / "problem.pddl"),
            )
            from osg_control.planning.api import plan_files

            fd_cost = plan_files(*files, planner="fast-downward").cost
    report = {
        "domain": domain.name,
        "objects": objects,
        "goal": goal,
        "planners": rows,
        "fast_downward_cost": fd_cost,
        "plan": list(result.actions) if result else [],
    }
    print(json.dumps(report, indent=2) if args.json else "\n".join(_lines(report, args.type)))


def _lines(report: dict[str, Any], kind: str) -> list[str]:
    """The report for humans: one line per planner, then Fast Downward's cost."""
    lines = [f"{report['domain']}: {len(report['objects'])} x {kind}; goal {report['goal']}"]
    lines += [
        f"  {row['planner']:<11} {row['status']:<8} cost {row['cost']} in {row['steps']} "
        f"steps; {row['ground_operators']} ground operators; grounding "
        f"{row['grounding_ms']} ms + search {row['search_ms']} ms = {row['total_ms']} ms "
        f"({row['ratio_to_target']} x the {TARGET_S * 1000:g} ms target)"
        for row in report["planners"]
    ]
    return [*lines, f"  Fast Downward cost: {report['fast_downward_cost']}"]


if __name__ == "__main__":
    main()
