"""The lifted PDDL domain ``osg-libero``: our operator schemas over LIBERO's task files.

LIBERO's task files state objects, init and goal, never actions: the operators are ours,
written once here (``SCHEMAS``). They use the skill graph's place and hand predicates
(docs/domains.md): ``(at home)`` for the fixed home node, ``(at-object near ?x)`` for the
node anchored in the frame of ``?x`` (above a movable object or a region, at a drawer's or
door's handle, at a knob), ``(hand-empty)`` and ``(holding ?o)``. As in the kitchen, the hand
moves between home and the things it acts on (``approach``, ``retreat``), so the operators
grow linearly with the scene. The goal predicates are LIBERO's own (``on``, ``in``,
``open``, ``close``, ``turnon``, ``turnoff``); which operator achieves each is derived from
the schemas' effects (``achievers``).

Types: ``movable``, ``fixture`` and ``region`` under ``thing``; each LIBERO object or
fixture category of the task files is a subtype of ``movable`` or ``fixture``
(``domain_types``). Every operator costs ``DEFAULT_COST`` (no skill's success rate is
measured yet), so a plan's cost is 100 per step.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from functools import cache

from pddl.action import Action
from pddl.core import Domain
from pddl.logic import Constant, Predicate, Variable
from pddl.logic.base import And, Formula, Not
from pddl.logic.functions import Increase, NumericValue
from pddl.logic.predicates import EqualTo
from pddl.requirements import Requirements

from osg_control.domain.lifted import AT, AT_OBJECT, NODE_TYPE, OBJECT_TYPE
from osg_control.libero.problem import LiberoProblem, TaskFileError
from osg_control.planning.pddl_io import DEFAULT_COST, TOTAL_COST

PDDL_DOMAIN = "osg-libero"
"""The lifted domain's PDDL name (the problems' ``(:domain ...)``)."""
THING, MOVABLE, FIXTURE, REGION = "thing", "movable", "fixture", "region"
"""Our types: what the hand acts on, split into LIBERO's objects, fixtures and regions."""
HOME, NEAR = "home", "near"
"""The nodes: the fixed home pose; the approach pose anchored to a thing (``at-object``)."""
BASE_TYPES: dict[str, str | None] = {
    NODE_TYPE: None, THING: None, MOVABLE: THING, FIXTURE: THING, REGION: THING
}  # fmt: skip
"""Type -> parent (None: ``object``, the root)."""

Lit = tuple[str, ...]
"""A lifted atom: predicate, then ``?variables`` or node constants."""

PREDICATES: dict[str, tuple[tuple[str, str], ...]] = {
    AT: (("n", NODE_TYPE),),
    AT_OBJECT: (("n", NODE_TYPE), ("x", THING)),
    "hand-empty": (),
    "holding": (("o", MOVABLE),),
    "on": (("x", THING), ("s", THING)),
    "in": (("x", THING), ("r", REGION)),
    "open": (("x", THING),),
    "close": (("x", THING),),
    "turnon": (("f", FIXTURE),),
    "turnoff": (("f", FIXTURE),),
    "door-of": (("x", THING), ("r", REGION)),
    "accessible": (("r", REGION),),
}
"""Predicate -> its typed parameters. ``on``/``in``/``open``/``close``/``turnon``/``turnoff``
are LIBERO's; ``door-of`` (static) and ``accessible`` come from ``articulation``."""


@dataclass(frozen=True)
class Schema:
    """One operator: typed parameters, preconditions, add and delete atoms, and the pairs
    of parameters that must name different things."""

    name: str
    parameters: tuple[tuple[str, str], ...]
    pre: tuple[Lit, ...]
    add: tuple[Lit, ...] = ()
    delete: tuple[Lit, ...] = ()
    distinct: tuple[tuple[str, str], ...] = ()


def _near(var: str) -> Lit:
    return (AT_OBJECT, NEAR, var)


def _hand_op(name: str, var: str, kind: str, before: str, after: str) -> Schema:
    """A fixture operator by the empty hand at the thing's handle or knob:
    ``(before ?x)`` -> ``(after ?x)``."""
    return Schema(name, ((var, kind),), (_near(var), ("hand-empty",), (before, var)),
                  ((after, var),), ((before, var),))  # fmt: skip


def _door_op(name: str, before: str, after: str, access: bool) -> Schema:
    """open/close(?x ?r): the drawer or door ``?x`` and the region ``?r`` behind it."""
    base = _hand_op(name, "?x", THING, before, after)
    gate = ("accessible", "?r")
    return Schema(
        name, (("?x", THING), ("?r", REGION)), (*base.pre, ("door-of", "?x", "?r")),
        (*base.add, *((gate,) if access else ())), (*base.delete, *(() if access else (gate,))),
    )  # fmt: skip


def _place(name: str, target: str, kind: str, relation: str, *pre: Lit) -> Schema:
    """Put the held object ``?o`` ``relation`` the thing the hand is near (never itself)."""
    return Schema(
        name, (("?o", MOVABLE), (target, kind)),
        (_near(target), ("holding", "?o"), *pre),
        ((relation, "?o", target), ("hand-empty",)), (("holding", "?o"),),
        distinct=((("?o", target),) if kind != REGION else ()),
    )  # fmt: skip


def _pick(name: str, support: str, kind: str, relation: str, *pre: Lit) -> Schema:
    """Grasp and lift ``?o`` from ``relation`` ``support`` with the empty hand."""
    return Schema(
        name, (("?o", MOVABLE), (support, kind)),
        (_near("?o"), ("hand-empty",), (relation, "?o", support), *pre),
        (("holding", "?o"),), (("hand-empty",), (relation, "?o", support)),
    )  # fmt: skip


PICKS = ("pick", "pick-out")
"""The operators that take an object into the hand (off a thing, out of a region)."""
PLACES = ("place-on", "place-in")
"""The operators that set the held object down (on a thing, into a region)."""

SCHEMAS: tuple[Schema, ...] = (
    Schema("approach", (("?x", THING),), ((AT, HOME),), (_near("?x"),), ((AT, HOME),)),
    Schema("retreat", (("?x", THING),), (_near("?x"),), ((AT, HOME),), (_near("?x"),)),
    _pick(PICKS[0], "?s", THING, "on"),
    _pick(PICKS[1], "?r", REGION, "in", ("accessible", "?r")),
    _place(PLACES[0], "?t", THING, "on"),
    _place(PLACES[1], "?r", REGION, "in", ("accessible", "?r")),
    _door_op("open", "close", "open", access=True),
    _door_op("close", "open", "close", access=False),
    _hand_op("turn-on", "?f", FIXTURE, "turnoff", "turnon"),
    _hand_op("turn-off", "?f", FIXTURE, "turnon", "turnoff"),
)
"""The operators, each ``DEFAULT_COST``. Moves go through home; ``pick``/``place-*`` keep
the hand at the node near the thing they act on."""


@cache
def achievers() -> dict[str, tuple[str, ...]]:
    """Predicate -> the operators whose effects make it true (derived from ``SCHEMAS``)."""
    found: dict[str, list[str]] = {}
    for schema in SCHEMAS:
        for atom in schema.add:
            found.setdefault(atom[0], []).append(schema.name)
    return {p: tuple(names) for p, names in found.items()}


def domain_types(problems: Iterable[LiberoProblem]) -> dict[str, str | None]:
    """Our types plus each LIBERO category of the task files under ``movable`` or
    ``fixture``.

    Raises:
        TaskFileError: a category that is an object in one file and a fixture in another,
            or that is one of our own type names.
    """
    types = dict(BASE_TYPES)
    for problem in problems:
        for group, parent in ((problem.objects, MOVABLE), (problem.fixtures, FIXTURE)):
            for kind in sorted(set(group.values())):
                if kind in (*BASE_TYPES, OBJECT_TYPE):
                    raise TaskFileError(f"{problem.path}: the category {kind!r} is our type")
                if types.setdefault(kind, parent) != parent:
                    raise TaskFileError(
                        f"{problem.path}: the category {kind!r} is a {parent} here and a "
                        f"{types[kind]} in another task file"
                    )
    return types


def _variable(name: str, kind: str) -> Variable:
    return Variable(name[1:], [kind])


def _formula(atom: Lit, variables: dict[str, Variable]) -> Predicate:
    terms = [variables[a] if a.startswith("?") else Constant(a) for a in atom[1:]]
    return Predicate(atom[0], *terms)


def _action(schema: Schema) -> Action:
    variables = {v: _variable(v, kind) for v, kind in schema.parameters}
    pre: list[Formula] = [_formula(a, variables) for a in schema.pre]
    pre += [Not(EqualTo(variables[a], variables[b])) for a, b in schema.distinct]
    effect: list[Formula] = [_formula(a, variables) for a in schema.add]
    effect += [Not(_formula(a, variables)) for a in schema.delete]
    effect.append(Increase(TOTAL_COST, NumericValue(DEFAULT_COST)))
    return Action(schema.name, list(variables.values()), precondition=And(*pre),
                  effect=And(*effect))  # fmt: skip


def libero_domain(problems: Iterable[LiberoProblem]) -> Domain:
    """The domain ``osg-libero`` typed for the task files' categories (``domain_types``).

    Raises:
        TaskFileError: see ``domain_types``.
    """
    predicates = [
        Predicate(name, *(_variable(f"?{v}", kind) for v, kind in params))
        for name, params in PREDICATES.items()
    ]
    return Domain(
        PDDL_DOMAIN,
        requirements=[Requirements.STRIPS, Requirements.TYPING, Requirements.EQUALITY,
                      Requirements.ACTION_COSTS],
        types=domain_types(problems),
        constants=[Constant(HOME, type_tag=NODE_TYPE), Constant(NEAR, type_tag=NODE_TYPE)],
        predicates=predicates,
        functions={TOTAL_COST: None},
        actions=[_action(s) for s in SCHEMAS],
    )  # fmt: skip
