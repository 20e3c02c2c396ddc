"""The planner registry and the entry points: plan for a domain's goal, or for PDDL files."""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from pddl.core import Domain, Problem

from osg_control.domain.base import Domain as OSGDomain
from osg_control.errors import PlanningError
from osg_control.planning.fast_downward import run_fast_downward
from osg_control.planning.graph import SkillGraph, graph_from_specs
from osg_control.planning.grounding import ground
from osg_control.planning.heuristics import HMax, blind
from osg_control.planning.pddl_io import (
    build_domain,
    build_problem,
    pddl_domain_name,
    read_domain,
    read_problem,
    write_pddl,
)
from osg_control.planning.search import best_first_search
from osg_control.planning.task import PlanResult, Task


@dataclass(frozen=True)
class Instance:
    """A planning problem in every form a backend may want.

    Attributes:
        domain: the parsed or generated domain.
        problem: the problem.
        task: their grounding.
        files: the PDDL files they came from, if any (else backends that need files write
            them).
    """

    domain: Domain
    problem: Problem
    task: Task
    files: tuple[Path, Path] | None = None


Planner = Callable[[Instance], PlanResult]


def _astar(instance: Instance) -> PlanResult:
    return best_first_search(instance.task, HMax(instance.task), "astar")


def _ucs(instance: Instance) -> PlanResult:
    return best_first_search(instance.task, blind, "ucs")


def _fast_downward(instance: Instance) -> PlanResult:
    if instance.files is not None:
        return run_fast_downward(instance.task, *instance.files)
    with tempfile.TemporaryDirectory(prefix="osg-pddl-") as tmp:
        domain_file = write_pddl(instance.domain, Path(tmp) / "domain.pddl")
        problem_file = write_pddl(instance.problem, Path(tmp) / "problem.pddl")
        return run_fast_downward(instance.task, domain_file, problem_file)


PLANNERS: dict[str, Planner] = {
    "astar": _astar,
    "fast-downward": _fast_downward,
    "ucs": _ucs,
}
"""Planners by CLI name: A* with h_max (optimal), Fast Downward (``seq-opt-lmcut``,
optimal), and uniform-cost search (optimal, exhaustive; the reference for tests)."""


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
    domain: Domain, problem: Problem, planner: str = "astar", files: tuple[Path, Path] | None = None
) -> PlanResult:
    """Ground and plan.

    Args:
        domain: the domain.
        problem: the problem.
        planner: a ``PLANNERS`` name.
        files: the PDDL files ``domain`` and ``problem`` were read from, if any.

    Returns:
        The plan or a "no plan" result.

    Raises:
        PlanningError: an unknown planner, or the backend failed.
        PDDLError: the PDDL uses something the planner does not support.
    """
    backend = get_planner(planner)
    return backend(Instance(domain, problem, ground(domain, problem), files))


def plan_files(
    domain_file: str | Path, problem_file: str | Path, planner: str = "astar"
) -> PlanResult:
    """Plan for any STRIPS + typing + action-costs domain/problem pair.

    Raises:
        PDDLError: a file is missing, malformed or unsupported (file and line named).
        PlanningError: an unknown planner, or the backend failed.
    """
    files = (Path(domain_file), Path(problem_file))
    return solve(read_domain(files[0]), read_problem(files[1]), planner, files)


_SPEC_DOMAINS: dict[str, Domain] = {}


def graph_domain(domain: OSGDomain, graph: SkillGraph | None = None) -> Domain:
    """The PDDL domain of a skill graph (default: the domain's specs, uniform costs; that
    one is built once per domain, it never changes)."""
    if graph is not None:
        return build_domain(graph, pddl_domain_name(domain))
    if domain.name not in _SPEC_DOMAINS:
        _SPEC_DOMAINS[domain.name] = build_domain(
            graph_from_specs(domain), pddl_domain_name(domain)
        )
    return _SPEC_DOMAINS[domain.name]


def plan_for_goal(
    domain: OSGDomain,
    goal: str | Iterable[str],
    node: str | None = None,
    world: Iterable[str] | None = None,
    planner: str = "astar",
    graph: SkillGraph | None = None,
    pddl: Domain | None = None,
) -> PlanResult:
    """Plan a skill sequence for a goal of a domain.

    Args:
        domain: the domain.
        goal: facts to reach (e.g. two of the domain's facts separated by a space), or an
            ``(at NODE)`` atom.
        node: the node the robot starts at (default: the domain's ``home``).
        world: the world facts true at the start, all others false (default: the domain's
            ``start_world``).
        planner: a ``PLANNERS`` name.
        graph: the skill graph (with success rates for costs); default: the domain's specs.
        pddl: the PDDL domain of ``graph``, if the caller has built it already.

    Returns:
        The plan or a "no plan" result.

    Raises:
        PlanningError: an unknown goal fact, node or planner (the known ones listed), or the
            backend failed.
    """
    pddl = pddl if pddl is not None else graph_domain(domain, graph)
    node = domain.home if node is None else node
    world = domain.start_world if world is None else tuple(world)
    return plan_on_graph(pddl, goal, node, world, planner)


def plan_on_graph(
    graph: SkillGraph | Domain,
    goal: str | Iterable[str],
    node: str,
    world: Iterable[str],
    planner: str = "astar",
) -> PlanResult:
    """Plan over a skill graph (or its PDDL domain) from ``node`` with ``world`` true.

    Raises:
        PlanningError: an unknown goal fact, node or planner, or the backend failed.
    """
    get_planner(planner)
    pddl = build_domain(graph) if isinstance(graph, SkillGraph) else graph
    return solve(pddl, build_problem(pddl, node, world, goal, name="goal"), planner)
