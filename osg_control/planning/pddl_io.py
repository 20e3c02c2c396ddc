"""PDDL in and out: the skill graph as a domain, a world state plus goal as a problem, parse errors.

Built on the ``pddl`` package's object model, so everything written here parses back with
``pddl.parse_domain``/``parse_problem`` and with Fast Downward. Operator costs are integers
(Fast Downward's requirement): ``round(-ln(success_rate) * COST_SCALE)``, so a plan's total
cost is ``-COST_SCALE * ln`` of the probability that every skill in it succeeds and the
cheapest plan is the likeliest to succeed.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TypeVar

from pddl.action import Action
from pddl.core import Domain, Problem
from pddl.formatter import domain_to_string, problem_to_string
from pddl.logic import Constant, Predicate, Variable
from pddl.logic.base import And, Formula, Not
from pddl.logic.functions import EqualTo, Increase, Metric, NumericFunction, NumericValue
from pddl.parser.domain import DomainParser
from pddl.parser.problem import ProblemParser
from pddl.requirements import Requirements

from osg_control.domain.base import Domain as OSGDomain
from osg_control.domain.base import Task
from osg_control.errors import PDDLError, PlanningError
from osg_control.io_safety import atomic_write
from osg_control.planning.graph import SkillGraph, graph_from_specs

DOMAIN_PREFIX = "osg-"
"""A domain ``NAME`` is exported as the PDDL domain ``osg-NAME``."""
GRAPH_DOMAIN = "osg-graph"
"""The PDDL name of a skill graph that belongs to no registered domain."""
NODE_TYPE = "node"
AT = "at"
COST_SCALE = 1000
"""Cost units per nat of failure: a skill that succeeds with rate p costs -ln(p) * 1000."""
DEFAULT_COST = 100
"""Cost of a skill without a measured success rate (as if it succeeded 90.5 % of the time)."""
MIN_SUCCESS_RATE = 1e-3
"""Rates below this are clamped (cost 6908), so a never-successful skill stays finite."""
TOTAL_COST = NumericFunction("total-cost")

Atom = tuple[str, ...]
"""A ground atom as names: ``("door-open",)`` or ``("at", "home")``."""


def skill_cost(success_rate: float | None) -> int:
    """The integer operator cost of a skill.

    Args:
        success_rate: measured success rate in [0, 1], or None when unknown.

    Returns:
        ``DEFAULT_COST`` when unknown, else ``max(1, round(-ln(rate) * COST_SCALE))`` with the
        rate clamped to ``MIN_SUCCESS_RATE`` from below.
    """
    if success_rate is None:
        return DEFAULT_COST
    rate = max(success_rate, MIN_SUCCESS_RATE)
    return max(1, round(-math.log(rate) * COST_SCALE))


def pddl_domain_name(domain: OSGDomain) -> str:
    """The PDDL name of a domain's skill-graph domain (``osg-NAME``)."""
    return f"{DOMAIN_PREFIX}{domain.name}"


def build_domain(graph: SkillGraph, name: str = GRAPH_DOMAIN) -> Domain:
    """Export a skill graph as a STRIPS domain with typing and action costs.

    Nodes become constants of type ``node``; each skill becomes a parameterless operator named
    after it: pre ``(at start)`` plus its world preconditions, effects ``(at end)``,
    ``(not (at start))``, its add/delete facts and ``(increase (total-cost) C)``.

    Args:
        graph: the skill graph.
        name: the PDDL domain name.

    Returns:
        The domain object (write it with ``write_pddl``).
    """
    nodes = {n: Constant(n, type_tag=NODE_TYPE) for n in graph.node_names}
    at = {n: Predicate(AT, node) for n, node in nodes.items()}
    facts = {f: Predicate(f) for f in graph.facts}
    actions = []
    for edge in graph.edges:
        effects: list[Formula] = [facts[f] for f in edge.add_effects]
        effects += [Not(facts[f]) for f in edge.del_effects]
        # Also for a self-loop: add wins over delete, and the effect stays an (and ...).
        effects += [at[edge.end], Not(at[edge.start])]
        cost = skill_cost(edge.success_rate) + edge.step_cost
        effects.append(Increase(TOTAL_COST, NumericValue(cost)))
        pre = And(at[edge.start], *(facts[f] for f in edge.preconditions))
        actions.append(Action(edge.name, [], precondition=pre, effect=And(*effects)))
    return Domain(
        name,
        requirements=[Requirements.STRIPS, Requirements.TYPING, Requirements.ACTION_COSTS],
        types={NODE_TYPE: None},
        constants=list(nodes.values()),
        predicates=[Predicate(AT, Variable("n", [NODE_TYPE])), *facts.values()],
        functions={TOTAL_COST: None},
        actions=actions,
    )


_ATOM = re.compile(r"\(([^()]*)\)|([^\s()]+)")


def parse_atoms(text: str | Iterable[str]) -> tuple[Atom, ...]:
    """Read atoms written as ``door-open``, ``(door-open)`` or ``(at home)``.

    Args:
        text: one string of whitespace-separated atoms, or an iterable of such strings.

    Returns:
        The atoms, in order, without duplicates.

    Raises:
        PlanningError: unbalanced parentheses or an empty ``()``.
    """
    joined = text if isinstance(text, str) else " ".join(text)
    atoms: list[Atom] = []
    position = 0
    for match in _ATOM.finditer(joined):
        if joined[position : match.start()].strip():
            break
        atom = tuple((match.group(1) if match.group(1) is not None else match.group(2)).split())
        if not atom:
            raise PlanningError(f"empty atom '()' in {joined!r}")
        if atom not in atoms:
            atoms.append(atom)
        position = match.end()
    if joined[position:].strip():
        raise PlanningError(f"cannot read atoms from {joined!r} at {joined[position:]!r}")
    return tuple(atoms)


def check_atoms(atoms: Iterable[Atom], domain: Domain) -> None:
    """Check atoms against the domain's predicates (name and arity) and constants (the nodes).

    Args:
        atoms: the atoms to check.
        domain: the domain that declares the predicates and constants.

    Raises:
        PlanningError: naming the unknown predicate or object and listing the known ones.
    """
    arity = {p.name: p.arity for p in domain.predicates}
    known_objects = {c.name for c in domain.constants}
    for atom in atoms:
        name, args = atom[0], atom[1:]
        if name not in arity:
            raise PlanningError(
                f"unknown predicate {name!r}; known predicates: {', '.join(sorted(arity))}"
            )
        if len(args) != arity[name]:
            raise PlanningError(
                f"predicate {name!r} takes {arity[name]} argument(s), got {len(args)} in "
                f"({' '.join(atom)})"
            )
        for arg in args:
            if arg not in known_objects:
                raise PlanningError(
                    f"unknown object {arg!r} in ({' '.join(atom)}); known objects: "
                    f"{', '.join(sorted(known_objects))}"
                )


def _predicates(atoms: Iterable[Atom], domain: Domain) -> list[Predicate]:
    constants = {c.name: c for c in domain.constants}
    return [Predicate(atom[0], *(constants[a] for a in atom[1:])) for atom in atoms]


def build_problem(
    domain: Domain,
    node: str,
    world: Iterable[str],
    goal: str | Iterable[str],
    name: str = "task",
) -> Problem:
    """A problem over ``domain``: the robot at ``node``, the world facts true, a goal.

    Args:
        domain: the domain (its constants are the nodes).
        node: the node the robot is at.
        world: the world facts that hold (names of 0-ary predicates); all others are false.
        goal: atoms to reach, e.g. ``"door-open cube-in-cabinet"`` or ``"(at home)"``.
        name: the problem name.

    Returns:
        The problem, minimising total cost.

    Raises:
        PlanningError: an unknown node, fact or goal atom (listing the known ones), or an
            empty goal.
    """
    init_atoms = ((AT, node), *((fact,) for fact in world))
    goal_atoms = parse_atoms(goal)
    if not goal_atoms:
        raise PlanningError("empty goal: name at least one fact to reach")
    check_atoms(init_atoms, domain)
    check_atoms(goal_atoms, domain)
    return Problem(
        name,
        domain=domain,
        init=[EqualTo(TOTAL_COST, NumericValue(0)), *_predicates(init_atoms, domain)],
        goal=And(*_predicates(goal_atoms, domain)),
        metric=Metric(TOTAL_COST, Metric.MINIMIZE),
    )


def task_problem(pddl: Domain, domain: OSGDomain, task: Task) -> Problem:
    """The problem of one of a domain's tasks over its PDDL domain ``pddl``."""
    return build_problem(
        pddl, domain.task_node(task), domain.task_world(task), task.goal, name=task.name
    )


def write_pddl(thing: Domain | Problem, path: str | Path, comment: str = "") -> Path:
    """Write a domain or problem as PDDL text, under an optional ``;`` comment header.

    Args:
        thing: the domain or problem.
        path: the file to write (parent folders are created).
        comment: lines to put first, each prefixed with ``; ``.

    Returns:
        The path written.
    """
    path = Path(path)
    text = domain_to_string(thing) if isinstance(thing, Domain) else problem_to_string(thing)
    header = "".join(f"; {line}\n" for line in comment.splitlines())
    return atomic_write(path, lambda tmp: tmp.write_text(header + text + "\n"))


def domain_comment(domain: OSGDomain) -> str:
    """The header of an exported domain file."""
    return (
        f"Offline Skill Graph domain {domain.name!r}, generated by `osg pddl export`; do not "
        f"edit.\nOperator cost = round(-ln(success rate) * {COST_SCALE}), at least 1; "
        f"{DEFAULT_COST} when no rate is known."
    )


def export_pddl(
    domain: OSGDomain, out_dir: str | Path, graph: SkillGraph | None = None
) -> list[Path]:
    """Write a domain's skill graph as a PDDL domain and its tasks as problems.

    Args:
        domain: the domain (its tasks become the problems).
        out_dir: receives ``osg-NAME.pddl`` and ``problems/<task>.pddl``.
        graph: the skill graph (default: the domain's specs, uniform costs).

    Returns:
        The paths written, domain first.
    """
    out = Path(out_dir)
    name = pddl_domain_name(domain)
    pddl = build_domain(graph if graph is not None else graph_from_specs(domain), name)
    paths = [write_pddl(pddl, out / f"{name}.pddl", domain_comment(domain))]
    for task in domain.tasks:
        comment = (
            f"{task.description}; from {domain.task_node(task)} with "
            f"{' '.join(domain.task_world(task))}"
        )
        paths.append(
            write_pddl(
                task_problem(pddl, domain, task), out / "problems" / f"{task.name}.pddl", comment
            )
        )
    return paths


_TERMINALS = {
    "LPAR": "'('",
    "RPAR": "')'",
    "NAME": "a name",
    "QMARK": "'?'",
    **{k.upper(): f"':{k}'" for k in ("action", "derived", "parameters", "precondition")},
    "EFFECT": "':effect'",
}
"""Readable names of the grammar's terminals, for "expected ..." in error messages."""


def _line_of(text: str, message: str) -> int | None:
    """The first line naming a quoted word of ``message`` (for errors lark gives no line)."""
    for word in re.findall(r"'([^'\s]+)'", message):
        pattern = re.compile(rf"(?<![\w-]){re.escape(word)}(?![\w-])")
        for number, line in enumerate(text.splitlines(), start=1):
            if pattern.search(line.split(";", 1)[0]):
                return number
    return None


def _describe(path: Path, text: str, err: Exception) -> str:
    """``path:line:column: what; expected what`` from a lark error, else the line guessed."""
    line = getattr(err, "line", None)
    expected = getattr(err, "expected", None) or getattr(err, "allowed", None) or ()
    names = ", ".join(sorted(_TERMINALS.get(str(e), str(e)) for e in expected))
    token = getattr(err, "token", None)
    if getattr(token, "type", "") == "$END":
        return f"{path}:{line}: unexpected end of file; expected {names} (unbalanced parentheses?)"
    if isinstance(line, int) and line > 0 and names:
        found = repr(str(token)) if token is not None else repr(getattr(err, "char", "?"))
        where = f"{path}:{line}:{getattr(err, 'column', '?')}"
        source = text.splitlines()[line - 1].strip()
        return f"{where}: unexpected {found}; expected {names}\n    {source}"
    message = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    number = _line_of(text, message)
    return f"{path}:{number}: {message}" if number is not None else f"{path}: {message}"


T = TypeVar("T")


def _read(path: str | Path, parse: Callable[[str], T], what: str) -> T:
    """Read and parse a file; callers pass a fresh parser (pddl's keep state between files)."""
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise PDDLError(f"{path}: {what} file not found") from None
    except (OSError, UnicodeDecodeError) as err:
        raise PDDLError(f"{path}: cannot read {what} file ({err})") from err
    try:
        return parse(text)
    except Exception as err:  # lark, pddl and builtin errors alike: all mean a bad file
        raise PDDLError(_describe(path, text, err)) from err


def read_domain(path: str | Path) -> Domain:
    """Parse a PDDL domain file.

    Raises:
        PDDLError: the file is missing or malformed; names the file, the line and what was
            expected there where the parser says.
    """
    return _read(path, DomainParser(), "domain")


def read_problem(path: str | Path) -> Problem:
    """Parse a PDDL problem file.

    Raises:
        PDDLError: the file is missing or malformed; names the file, the line and what was
            expected there where the parser says.
    """
    return _read(path, ProblemParser(), "problem")
