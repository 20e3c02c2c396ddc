"""``osg plan``: the cheapest skill sequence for a kitchen goal, or for any PDDL pair."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, TypeAlias

from osg_control.commands import domain_of
from osg_control.errors import PDDLError, PlanningError, UsageError
from osg_control.json_files import dump_json

if TYPE_CHECKING:
    from osg_control.planning.task import PlanResult

Verbs: TypeAlias = "argparse._SubParsersAction[argparse.ArgumentParser]"
NO_PLAN_EXIT = 3
"""Exit status when the planner proves there is no plan."""
UNKNOWN_EXIT = 4
"""Exit status when the search stopped at a limit (time, states) without an answer."""
PDDL_ERROR_EXIT = 5
"""Exit status for a PDDL file that is malformed, undeclared names, or unsupported."""
EXIT_STATUS = {"solved": 0, "unsolvable": NO_PLAN_EXIT, "unknown": UNKNOWN_EXIT}
PLANNER_NAMES = ("astar", "astar-hmax", "auto", "fast-downward", "ucs")
"""``planning.api.PLANNERS``' names, here so that building the parser imports no planner."""
EPILOG = (
    f"Exit status: 0 with a plan; {NO_PLAN_EXIT} when there is none (proved: a complete "
    f"search ran out); {UNKNOWN_EXIT} when a limit stopped the search first (unknown); "
    f"{PDDL_ERROR_EXIT} for a PDDL file that is malformed, names something undeclared or "
    "uses an unsupported construct; 1 on other errors; 2 on usage errors."
)


def format_plan(result: PlanResult) -> str:
    """A plan (or the unreached goal facts) as lines of text.

    Args:
        result: the planner's answer.

    Returns:
        The text, ending with the search statistics.
    """
    stats = result.stats
    goal = " ".join(result.goal)
    effort = (
        f"{stats.expanded} expanded, {stats.generated} generated states in "
        f"{stats.time_s * 1000:.1f} ms"
    )
    if result.status == "unknown":
        return f"unknown for {goal} [{result.planner}]: stopped at the {result.limit}\n{effort}"
    if result.steps is None:
        return (
            f"no plan for {goal} [{result.planner}]; goal facts unreached: "
            f"{' '.join(result.unreached)}\n{effort}"
        )
    width = max((len(step.action) for step in result.steps), default=0)
    lines = [f"plan for {goal} [{result.planner}]: {len(result.steps)} steps, cost {result.cost}"]
    lines += [
        f"{i:3d}. {step.action:<{width}}  {step.cost:6d}"
        for i, step in enumerate(result.steps, start=1)
    ]
    return "\n".join([*lines, effort])


def run_plan(args: argparse.Namespace) -> int:
    """Plan and print the result.

    Args:
        args: parsed ``osg plan`` arguments.

    Returns:
        0 with a plan, ``NO_PLAN_EXIT`` without one, ``UNKNOWN_EXIT`` at a limit,
        ``PDDL_ERROR_EXIT`` for a bad PDDL file (the error printed).

    Raises:
        PlanningError: neither or both of ``--goal`` and DOMAIN PROBLEM given, or not two
            files.
    """
    try:
        result = _plan(args)
    except PDDLError as err:
        print(f"osg: error: {err}", file=sys.stderr)
        return PDDL_ERROR_EXIT
    print(dump_json(result.to_dict()) if args.json else format_plan(result))
    return EXIT_STATUS[result.status]


def _plan(args: argparse.Namespace) -> PlanResult:
    """Plan for the files or the goal of ``args``, within its limits."""
    from osg_control.planning.api import plan_files, plan_for_goal
    from osg_control.planning.task import SearchLimits

    limits = SearchLimits(args.time_limit, args.max_states)
    if args.files:
        if args.goal is not None:
            raise PlanningError("give either DOMAIN PROBLEM or --goal, not both")
        if len(args.files) != 2:
            raise PlanningError(f"give a DOMAIN and a PROBLEM file, got {len(args.files)} file(s)")
        return plan_files(
            args.files[0],
            args.files[1],
            args.planner,
            limits,
            warn=lambda message: print(f"osg: warning: {message}", file=sys.stderr),
        )
    if args.goal is None:
        raise PlanningError(
            'give a goal (--goal "(door-open) (in-cabinet cube-1)") or DOMAIN PROBLEM files'
        )
    from osg_control.commands.checks import fact_atoms
    from osg_control.execution.bundle import measured_graph
    from osg_control.planning.graph import load_graph

    domain = domain_of(args)
    if args.graph and args.models:
        raise UsageError("--graph and --models both give the plan costs: give one")
    graph = load_graph(args.graph) if args.graph else measured_graph(domain, args.models)
    facts = None if args.facts is None else fact_atoms(domain, args.facts)
    return plan_for_goal(
        domain, args.goal, args.from_node, facts, args.planner, graph, limits=limits
    )


def register(subparsers: Verbs) -> None:
    """Add ``osg plan``."""
    parser = subparsers.add_parser(
        "plan",
        help="plan a skill sequence for a goal",
        description="Find the cheapest skill sequence (operator costs from success rates) "
        "for a goal of the domain, or solve a PDDL pair (STRIPS, typing, negative "
        "preconditions, equality, action costs; names case-insensitive).",
        epilog=EPILOG,
    )
    parser.add_argument(
        "files",
        nargs="*",
        type=Path,
        metavar="DOMAIN PROBLEM",
        help="PDDL domain and problem files (instead of --goal)",
    )
    parser.add_argument(
        "--goal",
        help='atoms to reach, e.g. "(door-open) (in-cabinet cube-1)", the fact names '
        '"door-open cube-in-cabinet", or "(at home)"',
    )
    parser.add_argument(
        "--from-node", default=None, help="start node (default: the domain's home node)"
    )
    parser.add_argument(
        "--facts",
        default=None,
        help="world facts (names or atoms) true at the start (default: the domain's)",
    )
    parser.add_argument(
        "--graph",
        type=Path,
        help="skill graph JSON with success rates (default: the domain's specs with the "
        "shipped defaults' measured success rates)",
    )
    parser.add_argument(
        "--models",
        type=Path,
        metavar="DIR",
        help="a defaults folder whose manifest's measured success rates set the costs (the "
        "same costs `osg run --models DIR` plans with)",
    )
    parser.add_argument(
        "--planner",
        choices=PLANNER_NAMES,
        default="auto",
        help="search (default: auto: the built-in A* with h_max within 1 s, then Fast "
        "Downward; astar: A* with LM-cut)",
    )
    parser.add_argument(
        "--time-limit",
        type=float,
        default=300.0,
        metavar="S",
        help="stop the search after S seconds with the answer unknown (default: 300)",
    )
    parser.add_argument(
        "--max-states",
        type=int,
        default=5_000_000,
        metavar="N",
        help="stop the built-in search once it holds N states (memory), answer unknown "
        "(default: 5000000)",
    )
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    parser.set_defaults(func=run_plan)
