"""The planner registry and the entry points: plan for a domain's goal, or for PDDL files."""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from pathlib import Path

from pddl.core import Domain, Problem

from osg_control.domain.base import Domain as OSGDomain
from osg_control.errors import PlanningError
from osg_control.planning.fast_downward import find_fast_downward, run_fast_downward
from osg_control.planning.graph import SkillGraph, graph_from_specs
from osg_control.planning.grounding import ground
from osg_control.planning.heuristics import HMax, blind
from osg_control.planning.lmcut import LMCut
from osg_control.planning.pddl_io import (
    SkillPDDL,
    build_domain,
    build_problem,
    pddl_domain_name,
    write_pddl,
)
from osg_control.planning.reader import read_pair
from osg_control.planning.search import best_first_search
from osg_control.planning.task import NO_LIMITS, PlanResult, SearchLimits, Task

AUTO_BUDGET = SearchLimits(time_s=1.0, max_states=100_000)
"""What ``auto`` lets the built-in search spend before it hands the task to Fast Downward."""


@dataclass(frozen=True)
class Instance:
    """A planning problem in every form a backend may want.

    Attributes:
        domain: the parsed or generated domain.
        problem: the problem.
        task: their grounding.
        files: the PDDL files they came from, if any (else backends that need files write
            them).
        limits: the bounds of the search.
    """

    domain: Domain
    problem: Problem
    task: Task
    files: tuple[Path, Path] | None = None
    limits: SearchLimits = NO_LIMITS


Planner = Callable[[Instance], PlanResult]


def _astar(instance: Instance) -> PlanResult:
    """A* with LM-cut."""
    return best_first_search(instance.task, LMCut(instance.task), "astar", instance.limits)


def _astar_hmax(instance: Instance) -> PlanResult:
    """A* with h_max (weaker than LM-cut, cheaper per state)."""
    return best_first_search(instance.task, HMax(instance.task), "astar-hmax", instance.limits)


def _ucs(instance: Instance) -> PlanResult:
    """Uniform-cost search: blind A*."""
    return best_first_search(instance.task, blind, "ucs", instance.limits)


def _fast_downward(instance: Instance) -> PlanResult:
    """Fast Downward on the instance's files (written to a temporary folder if it has none)."""
    if instance.files is not None:
        return run_fast_downward(instance.task, *instance.files, instance.limits)
    with tempfile.TemporaryDirectory(prefix="osg-pddl-") as tmp:
        domain_file = write_pddl(instance.domain, Path(tmp) / "domain.pddl")
        problem_file = write_pddl(instance.problem, Path(tmp) / "problem.pddl")
        return run_fast_downward(instance.task, domain_file, problem_file, instance.limits)


def _tighter(a: SearchLimits, b: SearchLimits) -> SearchLimits:
    """The smaller of each bound (None is unbounded)."""

    def least(x: float | None, y: float | None) -> float | None:
        return y if x is None else x if y is None else min(x, y)

    return SearchLimits(least(a.time_s, b.time_s), least(a.max_states, b.max_states))  # type: ignore[arg-type]


def _auto(instance: Instance) -> PlanResult:
    """A* with h_max within ``AUTO_BUDGET`` (cheapest per state: the skill graph plans in
    well under a millisecond); past it, Fast Downward with the time left, or, where it is
    not installed, A* with LM-cut within the caller's limits."""
    budget = _tighter(instance.limits, AUTO_BUDGET)
    first = _astar_hmax(replace(instance, limits=budget))
    if first.status != "unknown" or budget == instance.limits:
        return first
    spent = first.stats.time_s
    left = None if instance.limits.time_s is None else max(1.0, instance.limits.time_s - spent)
    rest = replace(instance, limits=replace(instance.limits, time_s=left))
    return _fast_downward(rest) if find_fast_downward() is not None else _astar(rest)


PLANNERS: dict[str, Planner] = {
    "auto": _auto,
    "astar": _astar,
    "astar-hmax": _astar_hmax,
    "fast-downward": _fast_downward,
    "ucs": _ucs,
}
"""Planners by CLI name: ``auto`` (the default: A* with h_max within a small budget, then
Fast Downward), A* with LM-cut or h_max, Fast Downward (``seq-opt-lmcut``), and
uniform-cost search (exhaustive; the reference for tests). All are optimal."""


def get_planner(name: str) -> Planner:
    """Look a planner up by name.

    Raises:
        PlanningError: an unknown name, listing the known ones.
    """
    try:
        return PLANNERS[name]
    except KeyError:
        raise PlanningError(
            f"unknown planner {name!r}; known planners: {', '.join(PLANNERS)}"
        ) from None


def solve(
    domain: Domain,
    problem: Problem,
    planner: str = "auto",
    files: tuple[Path, Path] | None = None,
    limits: SearchLimits = NO_LIMITS,
) -> PlanResult:
    """Ground and plan.

    Args:
        domain: the domain.
        problem: the problem.
        planner: a ``PLANNERS`` name.
        files: the PDDL files ``domain`` and ``problem`` were read from, if any.
        limits: the bounds of the search (reaching one gives the status "unknown").

    Returns:
        The plan or a "no plan" result.

    Raises:
        PlanningError: an unknown planner, or the backend failed.
        PDDLError: the PDDL uses something the planner does not support.
    """
    backend = get_planner(planner)
    return backend(Instance(domain, problem, ground(domain, problem), files, limits))


def plan_files(
    domain_file: str | Path,
    problem_file: str | Path,
    planner: str = "auto",
    limits: SearchLimits = NO_LIMITS,
    warn: Callable[[str], None] | None = None,
) -> PlanResult:
    """Plan for a domain/problem pair (STRIPS, typing, negative preconditions, equality,
    action costs; names case-insensitive).

    Args:
        domain_file: the PDDL domain.
        problem_file: the PDDL problem.
        planner: a ``PLANNERS`` name.
        limits: the bounds of the search.
        warn: called with each warning about the files (e.g. ``:types`` without ``:typing``).

    Raises:
        PDDLError: a file is missing, malformed, refers to an undeclared name or uses an
            unsupported construct (file, line and name given).
        PlanningError: an unknown planner, or the backend failed.
    """
    get_planner(planner)
    files = (Path(domain_file), Path(problem_file))
    pair = read_pair(*files)
    for message in pair.warnings:
        if warn is not None:
            warn(message)
    return solve(pair.domain, pair.problem, planner, files, limits)


_SPEC_DOMAINS: dict[str, SkillPDDL] = {}


def graph_domain(domain: OSGDomain, graph: SkillGraph | None = None) -> SkillPDDL:
    """The lifted PDDL domain of a skill graph (default: the domain's specs, uniform costs;
    that one is built once per domain, it never changes)."""
    if graph is not None:
        return build_domain(graph, pddl_domain_name(domain), domain.lifting)
    if domain.ref not in _SPEC_DOMAINS:
        _SPEC_DOMAINS[domain.ref] = build_domain(
            graph_from_specs(domain), pddl_domain_name(domain), domain.lifting
        )
    return _SPEC_DOMAINS[domain.ref]


def plan_for_goal(
    domain: OSGDomain,
    goal: str | Iterable[str],
    node: str | None = None,
    world: Iterable[str] | None = None,
    planner: str = "auto",
    graph: SkillGraph | None = None,
    pddl: SkillPDDL | None = None,
    limits: SearchLimits = NO_LIMITS,
) -> PlanResult:
    """Plan a skill sequence for a goal of a domain.

    Args:
        domain: the domain.
        goal: atoms to reach: the domain's fact names (``"door-open cube-in-cabinet"``),
            atoms over its objects (``"(in-cabinet cube-1)"``) or ``(at NODE)``.
        node: the node the robot starts at (default: the domain's ``home``).
        world: the world facts true at the start, all others false (default: the domain's
            ``start_world``).
        planner: a ``PLANNERS`` name.
        graph: the skill graph (with success rates for costs); default: the domain's specs.
        pddl: the PDDL domain of ``graph``, if the caller has built it already.
        limits: the bounds of the search.

    Returns:
        The plan or a "no plan" result; its steps name ground operators
        (``grab-cube cube-1``: the skill and its objects, ``lifted.Lifting.bind_step``).

    Raises:
        PlanningError: an unknown goal predicate, object, node or planner (the known ones
            listed), a wrong arity, or the backend failed.
    """
    pddl = pddl if pddl is not None else graph_domain(domain, graph)
    node = domain.home if node is None else node
    world = domain.start_world if world is None else tuple(world)
    return plan_on_graph(pddl, goal, node, world, planner, limits)


def plan_on_graph(
    graph: SkillGraph | SkillPDDL,
    goal: str | Iterable[str],
    node: str,
    world: Iterable[str],
    planner: str = "auto",
    limits: SearchLimits = NO_LIMITS,
) -> PlanResult:
    """Plan over a skill graph (or its PDDL domain) from ``node`` with ``world`` true.

    Raises:
        PlanningError: an unknown goal atom, node or planner, or the backend failed.
    """
    get_planner(planner)
    pddl = build_domain(graph) if isinstance(graph, SkillGraph) else graph
    problem = build_problem(pddl, node, world, goal, name="goal")
    return solve(pddl.domain, problem, planner, limits=limits)
