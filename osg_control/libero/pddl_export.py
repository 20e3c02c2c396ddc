"""LIBERO's task files as PDDL problems of the lifted domain ``osg-libero``.

Objects are typed by the task file (movable objects and fixtures by their LIBERO type,
regions as ``region``); ``:init`` and ``:goal`` are the file's atoms. A goal predicate that
none of the domain's operators achieves (``GOAL_OPERATORS``) is refused by name before
anything is written.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from pddl.core import Problem
from pddl.logic import Constant, Predicate
from pddl.logic.base import And
from pddl.requirements import Requirements

from osg_control.errors import UsageError
from osg_control.io_safety import check_output_dir
from osg_control.libero.problem import Atom, LiberoProblem
from osg_control.planning.pddl_io import write_pddl

PDDL_DOMAIN = "osg-libero"
"""The lifted domain the problems are written for (its operators: ``GOAL_OPERATORS``)."""
REGION_TYPE = "region"
"""The PDDL type of a task file's regions (objects and fixtures keep their LIBERO type)."""

GOAL_OPERATORS: dict[str, str] = {
    "on": "place-on",
    "in": "place-in",
    "open": "open",
    "close": "close",
    "turnon": "turn-on",
    "turnoff": "turn-off",
}
"""Goal predicate -> the lifted domain's operator that makes it true. The operators come
with the lifted skills (docs/libero.md: not shipped yet); this is their vocabulary."""


class UnsupportedPredicateError(UsageError):
    """A task's goal uses a predicate no operator achieves (exit 2, nothing written)."""


def check_goals(problems: Iterable[LiberoProblem]) -> None:
    """Refuse goals with a predicate that no operator achieves.

    Raises:
        UnsupportedPredicateError: naming each such predicate and the tasks that use it.
    """
    missing: dict[str, list[str]] = {}
    for problem in problems:
        for atom in problem.goal:
            if atom.predicate not in GOAL_OPERATORS:
                missing.setdefault(atom.predicate, []).append(f"{problem.suite}:{problem.index}")
    if missing:
        listed = "; ".join(f"{p!r} (tasks {', '.join(t)})" for p, t in sorted(missing.items()))
        raise UnsupportedPredicateError(
            f"no operator achieves the goal predicate(s) {listed}; operators exist for "
            f"{sorted(GOAL_OPERATORS)}"
        )


def problem_name(problem: LiberoProblem) -> str:
    """The PDDL problem's name: ``<suite>-<index>``."""
    return f"{problem.suite}-{problem.index}"


def to_pddl(problem: LiberoProblem) -> Problem:
    """The task as a PDDL problem over ``osg-libero`` (typed objects, init, goal)."""
    constants = {
        **{name: Constant(name, type_tag=t) for name, t in problem.objects.items()},
        **{name: Constant(name, type_tag=t) for name, t in problem.fixtures.items()},
        **{name: Constant(name, type_tag=REGION_TYPE) for name in problem.regions},
    }

    def predicate(atom: Atom) -> Predicate:
        return Predicate(atom.predicate, *(constants[a] for a in atom.args))

    return Problem(
        problem_name(problem),
        domain_name=PDDL_DOMAIN,
        requirements=[Requirements.TYPING],
        objects=list(constants.values()),
        init=[predicate(a) for a in problem.init],
        goal=And(*(predicate(a) for a in problem.goal)),
    )


def export_problems(problems: list[LiberoProblem], out_dir: str | Path) -> list[Path]:
    """Write ``<index>-<task name>.pddl`` per task under ``out_dir``, after checking every
    goal (nothing is written when one is refused).

    Raises:
        UnsupportedPredicateError: see ``check_goals``.
        OutputError: ``out_dir`` cannot be written.
    """
    check_goals(problems)
    out = check_output_dir(out_dir, "PDDL output folder")
    return [
        write_pddl(
            to_pddl(p),
            out / f"{p.index:02d}-{p.name}.pddl",
            f"LIBERO {p.suite} task {p.index}: {p.name}\nfrom {p.path.name}; instruction: "
            f"{p.language}",
        )
        for p in problems
    ]
