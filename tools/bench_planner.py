"""Benchmark the planners: the kitchen tasks and random skill graphs of 10, 100 and 1,000 skills.

Built-in A* (h_max) beside Fast Downward (seq-opt-lmcut) on the same problems, one row per
problem. "A* total" is what ``plan_for_goal`` costs end to end (PDDL objects, grounding,
search; median of ``--repeats`` runs); "A* search" is the search alone. "FD" is Fast
Downward's wall time: files written, process start, translator and search.

    python tools/bench_planner.py [--sizes 10 100 1000] [--goals 3] [--repeats 5] [--json]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from dataclasses import asdict, dataclass

from osg_control.domain.registry import get_domain
from osg_control.kitchen.tasks import KITCHEN_TASKS
from osg_control.planning.api import plan_on_graph
from osg_control.planning.fast_downward import find_fast_downward
from osg_control.planning.graph import SkillGraph, graph_from_specs
from osg_control.planning.synthetic import random_goal, random_skill_graph
from osg_control.planning.task import PlanResult


@dataclass(frozen=True)
class Problem:
    """One benchmark problem: a start, a goal and the graph."""

    name: str
    skills: int
    node: str
    world: tuple[str, ...]
    goal: tuple[str, ...]
    graph: SkillGraph


@dataclass(frozen=True)
class Row:
    """The measurements for one problem."""

    problem: str
    skills: int
    plan_length: int | None
    cost: int | None
    astar_total_ms: float
    astar_search_ms: float
    expanded: int
    fd_ms: float | None
    fd_cost: int | None
    agree: bool | None


def problems(sizes: list[int], goals: int) -> list[Problem]:
    """The kitchen tasks, then ``goals`` random goals per random graph size."""
    kitchen = graph_from_specs(get_domain("kitchen"))
    found = [
        Problem(f"kitchen:{t.name}", len(kitchen.edges), t.node, t.world, t.goal, kitchen)
        for t in KITCHEN_TASKS
    ]
    for size in sizes:
        graph = random_skill_graph(size, seed=size)
        for seed in range(goals):
            goal = random_goal(graph, seed=seed, num_goal_facts=1 + seed % 2)
            found.append(
                Problem(f"random-{size}:{seed}", size, goal.node, goal.world, goal.goal, graph)
            )
    return found


def _plan(problem: Problem, planner: str) -> tuple[PlanResult, float]:
    start = time.perf_counter()
    result = plan_on_graph(problem.graph, problem.goal, problem.node, problem.world, planner)
    return result, time.perf_counter() - start


def measure(problem: Problem, repeats: int, with_fd: bool) -> Row:
    """Time A* ``repeats`` times after a warm-up run (median) and Fast Downward once."""
    runs = [_plan(problem, "astar") for _ in range(repeats + 1)][1:]
    result = runs[0][0]
    fd, fd_s = _plan(problem, "fast-downward") if with_fd else (None, None)
    return Row(
        problem=problem.name,
        skills=problem.skills,
        plan_length=len(result.actions) if result.solved else None,
        cost=result.cost,
        astar_total_ms=statistics.median(s for _, s in runs) * 1000,
        astar_search_ms=statistics.median(r.stats.time_s for r, _ in runs) * 1000,
        expanded=result.stats.expanded,
        fd_ms=None if fd_s is None else fd_s * 1000,
        fd_cost=None if fd is None else fd.cost,
        agree=None if fd is None else fd.cost == result.cost,
    )


def _cell(value: object) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.2f}" if value < 100 else f"{value:.0f}"
    return str(value)


def table(rows: list[Row]) -> str:
    """The rows as an aligned text table."""
    header = (
        "problem",
        "skills",
        "steps",
        "cost",
        "A* total ms",
        "A* search ms",
        "expanded",
        "FD ms",
        "FD cost",
        "agree",
    )
    cells = [header] + [tuple(_cell(v) for v in asdict(row).values()) for row in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    lines = [
        "  ".join(
            c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True))
        )
        for r in cells
    ]
    lines.insert(1, "-" * len(lines[0]))
    return "\n".join(lines)


def main() -> int:
    """Run the benchmark and print the table (or JSON)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--sizes",
        type=int,
        nargs="+",
        default=[10, 100, 1000],
        help="random skill graph sizes (default: 10 100 1000)",
    )
    parser.add_argument("--goals", type=int, default=3, help="random goals per size")
    parser.add_argument("--repeats", type=int, default=5, help="A* runs per problem (median)")
    parser.add_argument("--no-fd", action="store_true", help="skip Fast Downward")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args()
    with_fd = not args.no_fd and find_fast_downward() is not None
    rows = [measure(p, args.repeats, with_fd) for p in problems(args.sizes, args.goals)]
    if args.json:
        machine = {
            "python": platform.python_version(),
            "machine": platform.machine(),
            "processor": platform.processor(),
        }
        print(json.dumps({"machine": machine, "rows": [asdict(r) for r in rows]}, indent=2))
    else:
        print(table(rows))
        if not with_fd:
            print("Fast Downward skipped" + ("" if args.no_fd else " (driver not found)"))
    return 0 if all(row.agree in (None, True) for row in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
