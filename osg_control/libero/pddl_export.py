"""LIBERO's task files as PDDL problems of the lifted domain ``osg-libero`` (``operators``),
and that domain written beside them.

Objects are typed by the task file (movable objects and fixtures by their LIBERO category,
regions as ``region``); ``:init`` is the file's atoms, the hand at home and empty, and what
the file leaves unsaid about drawers, doors and knobs (``articulation.implied_init``);
``:goal`` is the file's goal. A goal predicate that no operator achieves
(``operators.achievers``) is refused by name before anything is written.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from pddl.core import Domain, Problem
from pddl.logic import Constant, Predicate
from pddl.logic.base import And
from pddl.logic.functions import EqualTo, Metric, NumericValue

from osg_control.domain.lifted import AT
from osg_control.errors import UsageError
from osg_control.io_safety import check_output_dir
from osg_control.libero.articulation import implied_init
from osg_control.libero.operators import HOME, PDDL_DOMAIN, REGION, achievers, libero_domain
from osg_control.libero.problem import Atom, LiberoProblem
from osg_control.planning.pddl_io import TOTAL_COST, write_pddl


class UnsupportedPredicateError(UsageError):
    """A task's goal uses a predicate no operator achieves (exit 2, nothing written)."""


def check_goals(problems: Iterable[LiberoProblem]) -> None:
    """Refuse goals with a predicate that no operator achieves.

    Raises:
        UnsupportedPredicateError: naming each such predicate and the tasks that use it.
    """
    operators = achievers()
    missing: dict[str, list[str]] = {}
    for problem in problems:
        for atom in problem.goal:
            if atom.predicate not in operators:
                missing.setdefault(atom.predicate, []).append(f"{problem.suite}:{problem.index}")
    if missing:
        listed = "; ".join(f"{p!r} (tasks {', '.join(t)})" for p, t in sorted(missing.items()))
        known = ", ".join(f"{p} ({'/'.join(ops)})" for p, ops in sorted(operators.items()))
        raise UnsupportedPredicateError(
            f"no plan: no operator of {PDDL_DOMAIN} achieves the goal predicate(s) {listed}; "
            f"the operators achieve {known}"
        )


def problem_name(problem: LiberoProblem) -> str:
    """The PDDL problem's name: ``<suite>-<index>``."""
    return f"{problem.suite}-{problem.index}"


def init_atoms(problem: LiberoProblem) -> tuple[Atom, ...]:
    """The problem's init: the hand at home and empty, the file's atoms, and what it leaves
    unsaid about drawers, doors and knobs."""
    return (Atom(AT, (HOME,)), Atom("hand-empty", ()), *problem.init, *implied_init(problem))


def to_pddl(problem: LiberoProblem, domain: Domain | None = None) -> Problem:
    """The task as a PDDL problem over ``osg-libero`` (typed objects, init, goal, minimising
    total cost); over ``domain`` when given (checked against it), else by name."""
    constants = {
        **{name: Constant(name, type_tag=t) for name, t in problem.objects.items()},
        **{name: Constant(name, type_tag=t) for name, t in problem.fixtures.items()},
        **{name: Constant(name, type_tag=REGION) for name in problem.regions},
    }

    def predicate(atom: Atom) -> Predicate:
        return Predicate(atom.predicate, *(constants.get(a) or Constant(a) for a in atom.args))

    by_domain = {"domain": domain} if domain is not None else {"domain_name": PDDL_DOMAIN}
    return Problem(
        problem_name(problem),
        **by_domain,  # type: ignore[arg-type]
        objects=list(constants.values()),
        init=[EqualTo(TOTAL_COST, NumericValue(0)), *(predicate(a) for a in init_atoms(problem))],
        goal=And(*(predicate(a) for a in problem.goal)),
        metric=Metric(TOTAL_COST, Metric.MINIMIZE),
    )


def export_problems(
    problems: list[LiberoProblem], out_dir: str | Path, typed_for: Iterable[LiberoProblem] = ()
) -> list[Path]:
    """Write the domain ``osg-libero.pddl`` and ``<index>-<task name>.pddl`` per task under
    ``out_dir``, after checking every goal (nothing is written when one is refused).

    Args:
        problems: the tasks to write.
        out_dir: the folder.
        typed_for: more tasks whose categories the domain declares (the whole suite, so
            that the domain serves every problem of the folder).

    Raises:
        UnsupportedPredicateError: see ``check_goals``.
        TaskFileError: see ``operators.domain_types`` and ``articulation.implied_init``.
        OutputError: ``out_dir`` cannot be written.
    """
    check_goals(problems)
    domain = libero_domain([*problems, *typed_for])
    pddl_problems = [to_pddl(p) for p in problems]
    out = check_output_dir(out_dir, "PDDL output folder")
    header = (
        f"The lifted domain {PDDL_DOMAIN} (osg_control/libero/operators.py), typed for "
        f"{', '.join(sorted({p.suite for p in problems}))}; written by `osg --domain libero "
        "pddl export`; do not edit."
    )
    return [write_pddl(domain, out / f"{PDDL_DOMAIN}.pddl", header)] + [
        write_pddl(
            pddl,
            out / f"{p.index:02d}-{p.name}.pddl",
            f"LIBERO {p.suite} task {p.index}: {p.name}\nfrom {p.path.name}; instruction: "
            f"{p.language}",
        )
        for p, pddl in zip(problems, pddl_problems, strict=True)
    ]
