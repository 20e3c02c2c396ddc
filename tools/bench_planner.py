"""Benchmark the planners: the kitchen tasks, random skill graphs of 10, 100 and 1,000 skills,
and growing problems of classic STRIPS domains (gripper, blocks, logistics).

Skill graphs: ``--graph-planner`` (default ``auto``, the default of ``osg plan``) beside Fast
Downward (seq-opt-lmcut) on the same problems, one row per problem. "total" is what
``plan_on_graph`` costs end to end (PDDL objects, grounding, search; median of
``--repeats`` runs); "search" is the search alone.
"FD" is Fast Downward's wall time: files written, process start, translator and search.

Classic domains: each planner runs once per problem in a fresh process (``plan_files``
end to end, ``--time-limit`` each), reporting its status, cost, expanded states, wall time
and peak memory (the process's own, or Fast Downward's largest child process).

    python tools/bench_planner.py [--sizes 10 100 1000] [--goals 3] [--repeats 5] [--json]
        [--classic gripper:4,6,8 blocks:6,8 logistics:4,6] [--planners astar auto fast-downward]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from osg_control.domain.registry import get_domain
from osg_control.kitchen.tasks import KITCHEN_TASKS
from osg_control.planning.api import plan_on_graph
from osg_control.planning.classic import write_classic
from osg_control.planning.fast_downward import find_fast_downward
from osg_control.planning.graph import SkillGraph, graph_from_specs
from osg_control.planning.synthetic import random_goal, random_skill_graph
from osg_control.planning.task import PlanResult

_WORKER = """
import json, resource, sys
from osg_control.planning.api import plan_files
from osg_control.planning.task import SearchLimits
r = plan_files(sys.argv[1], sys.argv[2], sys.argv[3], SearchLimits(time_s=float(sys.argv[4])))
own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
child = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
print(json.dumps({"planner": r.planner, "status": r.status, "cost": r.cost,
                  "expanded": r.stats.expanded, "peak_mb": own / 1024,
                  "child_peak_mb": child / 1024}))
"""
"""One planner run in a fresh process, so that its peak memory is its own."""


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
    domain = get_domain("kitchen")
    kitchen = graph_from_specs(domain)
    found = [
        Problem(f"kitchen:{t.name}", len(kitchen.edges), t.node, t.world, t.goal, kitchen)
        for t in KITCHEN_TASKS
        if domain.runs_here(t)  # the one-cube scene's (its graph's facts are 0-ary names)
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
    """Plan once; the result and the wall seconds."""
    start = time.perf_counter()
    result = plan_on_graph(problem.graph, problem.goal, problem.node, problem.world, planner)
    return result, time.perf_counter() - start


def measure(problem: Problem, repeats: int, with_fd: bool, planner: str) -> Row:
    """Time ``planner`` ``repeats`` times after a warm-up run (median), Fast Downward once."""
    runs = [_plan(problem, planner) for _ in range(repeats + 1)][1:]
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
        "total ms",
        "search ms",
        "expanded",
        "FD ms",
        "FD cost",
        "agree",
    )
    return _aligned(header, [tuple(_cell(v) for v in asdict(row).values()) for row in rows])


@dataclass(frozen=True)
class ClassicRow:
    """One planner on one classic problem."""

    problem: str
    planner: str
    answered_by: str
    status: str
    cost: int | None
    expanded: int
    wall_s: float
    peak_mb: float
    child_peak_mb: float


def measure_classic(
    domain: str, size: int, planners: list[str], time_limit: float, out: Path
) -> list[ClassicRow]:
    """Run each planner once on the classic problem ``domain`` of ``size``."""
    files = write_classic(domain, size, out)
    rows = []
    for planner in planners:
        start = time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-c", _WORKER, *map(str, files), planner, str(time_limit)],
            capture_output=True,
            text=True,
            check=True,
        )
        wall = time.perf_counter() - start
        got = json.loads(done.stdout.strip().splitlines()[-1])
        rows.append(
            ClassicRow(
                f"{domain}-{size}",
                planner,
                got["planner"],
                got["status"],
                got["cost"],
                got["expanded"],
                wall,
                got["peak_mb"],
                got["child_peak_mb"],
            )
        )
    return rows


def _parse_classic(specs: list[str]) -> list[tuple[str, int]]:
    """``gripper:4,6`` -> ``[("gripper", 4), ("gripper", 6)]``."""
    found = []
    for spec in specs:
        name, _, sizes = spec.partition(":")
        found += [(name, int(size)) for size in sizes.split(",") if size]
    return found


def _aligned(header: tuple[str, ...], rows: list[tuple[str, ...]]) -> str:
    """Rows of cells as an aligned text table under ``header``."""
    cells = [header, *rows]
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
    parser.add_argument(
        "--graph-planner", default="auto", help="built-in planner on the skill graphs (auto)"
    )
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument(
        "--classic",
        nargs="*",
        default=["gripper:4,6,8", "blocks:6,8", "logistics:4,6"],
        metavar="DOMAIN:SIZES",
        help="classic problems, e.g. gripper:4,6,8 (none: skip them)",
    )
    parser.add_argument(
        "--planners",
        nargs="+",
        default=["astar", "auto", "fast-downward"],
        help="planners on the classic problems",
    )
    parser.add_argument(
        "--time-limit", type=float, default=30.0, help="seconds per classic run (default 30)"
    )
    args = parser.parse_args()
    with_fd = not args.no_fd and find_fast_downward() is not None
    planners = [p for p in args.planners if with_fd or p != "fast-downward"]
    with tempfile.TemporaryDirectory(prefix="osg-bench-") as tmp:
        classic = [
            row
            for name, size in _parse_classic(args.classic)
            for row in measure_classic(name, size, planners, args.time_limit, Path(tmp))
        ]
    rows = [
        measure(p, args.repeats, with_fd, args.graph_planner)
        for p in problems(args.sizes, args.goals)
    ]
    if args.json:
        machine = {
            "python": platform.python_version(),
            "machine": platform.machine(),
            "processor": platform.processor(),
        }
        payload = {"machine": machine, "rows": [asdict(r) for r in rows]}
        payload["classic"] = [asdict(r) for r in classic]
        print(json.dumps(payload, indent=2))
    else:
        print(table(rows))
        if classic:
            header = (
                "problem",
                "planner",
                "answered by",
                "status",
                "cost",
                "expanded",
                "wall s",
                "peak MB",
                "FD peak MB",
            )
            cells = [tuple(_cell(v) for v in asdict(r).values()) for r in classic]
            print("\n" + _aligned(header, cells))
        if not with_fd:
            print("Fast Downward skipped" + ("" if args.no_fd else " (driver not found)"))
    costs: dict[str, set[int]] = {}
    for row in classic:
        if row.cost is not None:
            costs.setdefault(row.problem, set()).add(row.cost)
    agree = all(len(found) == 1 for found in costs.values())
    return 0 if agree and all(row.agree in (None, True) for row in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
