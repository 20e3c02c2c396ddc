"""PDDL out: the skill graph as a typed lifted domain, a world state plus goal as a problem
(reading files with named errors: ``planning.pddl_parse``).

Built on the ``pddl`` package's object model, so everything written here parses back with
``pddl.parse_domain``/``parse_problem`` and with Fast Downward. Operator costs are integers
(Fast Downward's requirement): ``round(-ln(success_rate) * COST_SCALE)``, so a plan's total
cost is ``-COST_SCALE * ln`` of the probability that every skill in it succeeds and the
cheapest plan is the likeliest to succeed.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from pddl.action import Action
from pddl.core import Domain, Problem
from pddl.formatter import domain_to_string, problem_to_string
from pddl.logic import Constant, Predicate, Variable
from pddl.logic.base import And, Formula, Not
from pddl.logic.functions import EqualTo, Increase, Metric, NumericFunction, NumericValue
from pddl.requirements import Requirements

from osg_control.domain.base import Domain as OSGDomain
from osg_control.domain.base import Task
from osg_control.domain.lifted import (
    AT,
    AT_OBJECT,
    NODE_TYPE,
    OBJECT_TYPE,
    Atom,
    Lifting,
)
from osg_control.domain.spec import Node
from osg_control.errors import PlanningError
from osg_control.io_safety import atomic_write
from osg_control.planning.graph import SkillGraph, graph_from_specs

DOMAIN_PREFIX = "osg-"
"""A domain ``NAME`` is exported as the PDDL domain ``osg-NAME``."""
GRAPH_DOMAIN = "osg-graph"
"""The PDDL name of a skill graph that belongs to no registered domain."""
COST_SCALE = 1000
"""Cost units per nat of failure: a skill that succeeds with rate p costs -ln(p) * 1000."""
DEFAULT_COST = 100
"""Cost of a skill without a measured success rate (as if it succeeded 90.5 % of the time)."""
MIN_SUCCESS_RATE = 1e-3
"""Rates below this are clamped (cost 6908), so a never-successful skill stays finite."""
TOTAL_COST = NumericFunction("total-cost")


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


@dataclass(frozen=True)
class SkillPDDL:
    """A skill graph's PDDL domain and the lifted view it was written from (which the
    problems over it need to name their objects and atoms)."""

    domain: Domain
    lifting: Lifting


def graph_lifting(graph: SkillGraph) -> Lifting:
    """The lifting of a graph without a domain's declarations: 0-ary facts, fixed nodes."""
    nodes = {n.name: Node(n.name, n.position) for n in graph.nodes}
    return Lifting({}, (), (), (), graph.facts, nodes, ())


def _term(arg: str, lifting: Lifting, variables: dict[str, Variable]) -> Variable | Constant:
    if arg in variables:
        return variables[arg]
    if arg in lifting.instances:
        return Constant(arg, type_tag=lifting.instances[arg].type)
    return Constant(arg, type_tag=NODE_TYPE)


def _predicate(atom: Atom, lifting: Lifting, variables: dict[str, Variable]) -> Predicate:
    return Predicate(atom[0], *(_term(a, lifting, variables) for a in atom[1:]))


def _declared_predicates(lifting: Lifting, used: set[str]) -> list[Predicate]:
    """``(at ?n - node)``, ``(at-object ?n - node ?o - object)`` where an operator uses it,
    then the domain's predicates with their typed parameters."""
    found = [Predicate(AT, Variable("n", [NODE_TYPE]))]
    if AT_OBJECT in used:
        found.append(Predicate(AT_OBJECT, Variable("n", [NODE_TYPE]), _variable("o", OBJECT_TYPE)))
    for decl in lifting.predicates.values():
        found.append(Predicate(decl.name, *(_variable(v, t) for v, t in decl.parameters)))
    return found


def _variable(name: str, kind: str) -> Variable:
    """A typed variable; ``object`` (the root type) is written untyped, as PDDL reads it."""
    return Variable(name, [] if kind == OBJECT_TYPE else [kind])


def build_domain(
    graph: SkillGraph, name: str = GRAPH_DOMAIN, lifting: Lifting | None = None
) -> SkillPDDL:
    """Export a skill graph as a typed STRIPS domain with action costs.

    Nodes become constants of type ``node``; each skill becomes an operator named after it,
    with the typed parameters of its spec (``lifting``: the domain's lifted view; without
    one every fact is a 0-ary predicate and no operator has parameters): pre ``(at start)``
    (``(at-object start ?o)`` for a node anchored to an object) plus its world
    preconditions, effects the end's atom, ``(not start)``, its add/delete atoms and
    ``(increase (total-cost) C)``. Instances an operator names directly are ``:constants``.

    Args:
        graph: the skill graph (costs from its success rates).
        name: the PDDL domain name.
        lifting: the domain's lifted view (``Domain.lifting``), or None.

    Returns:
        The domain and its lifting (write the domain with ``write_pddl``).
    """
    lifting = lifting if lifting is not None else graph_lifting(graph)
    actions, used = [], set()
    for edge in graph.edges:
        spec = lifting.skills.get(edge.name)
        lifted = lifting.lift(
            edge.name,
            [(v[1:], t) for v, t in spec.parameters] if spec is not None else (),
            edge.start,
            edge.end,
            edge.preconditions,
            edge.add_effects,
            edge.del_effects,
        )
        variables = {v: _variable(v[1:], t) for v, t in lifted.parameters}

        def term(atom: Atom, variables: dict[str, Variable] = variables) -> Predicate:
            return _predicate(atom, lifting, variables)

        used |= {atom[0] for atom in lifted.atoms}
        effects: list[Formula] = [term(a) for a in lifted.add]
        effects += [Not(term(a)) for a in lifted.delete]
        # Also for a self-loop: add wins over delete, and the effect stays an (and ...).
        effects += [term(lifted.end), Not(term(lifted.start))]
        cost = skill_cost(edge.success_rate) + edge.step_cost
        effects.append(Increase(TOTAL_COST, NumericValue(cost)))
        pre = And(term(lifted.start), *(term(a) for a in lifted.pre))
        actions.append(
            Action(edge.name, list(variables.values()), precondition=pre, effect=And(*effects))
        )
    constants = [Constant(n, type_tag=NODE_TYPE) for n in graph.node_names]
    named = {arg for action in actions for arg in _constant_names(action)}
    constants += [
        Constant(i.name, type_tag=i.type) for i in lifting.instances.values() if i.name in named
    ]
    types: dict[str, str | None] = {NODE_TYPE: None}
    types.update({t: (None if p == OBJECT_TYPE else p) for t, p in lifting.types.items()})
    pddl = Domain(
        name,
        requirements=[Requirements.STRIPS, Requirements.TYPING, Requirements.ACTION_COSTS],
        types=types,
        constants=constants,
        predicates=_declared_predicates(lifting, used),
        functions={TOTAL_COST: None},
        actions=actions,
    )
    return SkillPDDL(pddl, lifting)


def _constant_names(action: Action) -> set[str]:
    """The objects an action's formulas name (not through its parameters)."""
    found = set()
    for formula in (action.precondition, action.effect):
        for part in getattr(formula, "operands", ()):
            atom = part.argument if isinstance(part, Not) else part
            for t in getattr(atom, "terms", ()):
                if isinstance(t, Constant):
                    found.add(str(t.name))
    return found


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


def _atoms(atoms: Iterable[Atom], lifting: Lifting) -> list[Atom]:
    """Atoms as a user writes them, resolved (declared fact names, anchored nodes) and
    checked.

    Raises:
        PlanningError: an unknown predicate, node or object, or a wrong arity (named).
    """
    resolved = [lifting.resolve(atom) for atom in atoms]
    for atom in resolved:
        lifting.check_atom(atom)
    return resolved


def build_problem(
    pddl: SkillPDDL,
    node: str,
    world: Iterable[str],
    goal: str | Iterable[str],
    name: str = "task",
) -> Problem:
    """A problem over ``pddl``: the robot at ``node``, the world facts true, a goal.

    Args:
        pddl: the domain (its constants are the nodes) and its lifting.
        node: the node the robot is at; ``NODE OBJ`` for an anchored node relative to
            another object than its frame's recorded one (``above-cube cube-2``).
        world: the world facts that hold (the domain's fact names, or atoms such as
            ``(lifted cube-2)``); all others are false.
        goal: atoms to reach, e.g. ``"door-open (in-cabinet cube-1)"`` or ``"(at home)"``.
        name: the problem name.

    Returns:
        The problem, minimising total cost; its ``:objects`` are the instances that are
        not the domain's constants.

    Raises:
        PlanningError: an unknown node, predicate or object, a wrong arity (listing the
            known ones), or an empty goal.
    """
    lifting = pddl.lifting
    goal_atoms = parse_atoms(goal)
    if not goal_atoms:
        raise PlanningError("empty goal: name at least one fact to reach")
    node, *at = node.split()  # "above-cube cube-2": the node relative to that object
    if node not in lifting.nodes:
        raise PlanningError(f"unknown node {node!r}; nodes: {', '.join(sorted(lifting.nodes))}")
    place = (AT_OBJECT, node, *at) if at else (AT, node)
    init_atoms = _atoms([place, *(lifting.atom(fact) for fact in world)], lifting)
    goal_resolved = _atoms(goal_atoms, lifting)
    constants = {str(c.name) for c in pddl.domain.constants}
    objects = [
        Constant(i.name, type_tag=i.type)
        for i in lifting.instances.values()
        if i.name not in constants
    ]
    no_variables: dict[str, Variable] = {}
    return Problem(
        name,
        domain=pddl.domain,
        objects=objects,
        init=[
            EqualTo(TOTAL_COST, NumericValue(0)),
            *(_predicate(a, lifting, no_variables) for a in init_atoms),
        ],
        goal=And(*(_predicate(a, lifting, no_variables) for a in goal_resolved)),
        metric=Metric(TOTAL_COST, Metric.MINIMIZE),
    )


def task_problem(pddl: SkillPDDL, domain: OSGDomain, task: Task) -> Problem:
    """The problem of one of a domain's tasks over its PDDL domain ``pddl``, naming the
    objects of the task's scene (``Domain.for_task``: e.g. two cubes)."""
    scene = domain.for_task(task)
    if scene is not domain:
        pddl = SkillPDDL(pddl.domain, scene.lifting)
    return build_problem(
        pddl, scene.task_node(task), scene.task_world(task), task.goal, name=task.name
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
    pddl = build_domain(
        graph if graph is not None else graph_from_specs(domain), name, domain.lifting
    )
    paths = [write_pddl(pddl.domain, out / f"{name}.pddl", domain_comment(domain))]
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
