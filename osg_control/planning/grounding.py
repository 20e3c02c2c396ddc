"""Ground a parsed STRIPS + typing + action-costs domain/problem into a ``Task``.

Anything beyond those three requirements (negative or disjunctive preconditions, equality,
conditional or quantified effects, derived predicates, numeric fluents) is rejected with a
``PDDLError`` that names the requirement, so no task is ever silently mis-read.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

from pddl.action import Action
from pddl.core import Domain, Problem
from pddl.logic import Constant, Predicate, Variable
from pddl.logic.base import And, ExistsCondition, ForallCondition, Formula, Imply, Not, Or
from pddl.logic.effects import Forall, When
from pddl.logic.functions import (
    Assign,
    Decrease,
    EqualTo,
    Increase,
    NumericFunction,
    NumericValue,
    ScaleDown,
    ScaleUp,
)
from pddl.logic.predicates import EqualTo as EqualityAtom
from pddl.requirements import Requirements

from osg_control.errors import PDDLError
from osg_control.planning.task import Fact, Operator, Task

SUPPORTED_REQUIREMENTS = frozenset(
    {Requirements.STRIPS, Requirements.TYPING, Requirements.ACTION_COSTS}
)
SUPPORTED = ":strips :typing :action-costs"
TOTAL_COST = "total-cost"
OBJECT = "object"

_NEEDS: dict[type, str] = {
    Not: ":negative-preconditions",
    Or: ":disjunctive-preconditions",
    Imply: ":disjunctive-preconditions",
    EqualityAtom: ":equality",
    ForallCondition: ":universal-preconditions",
    ExistsCondition: ":existential-preconditions",
    When: ":conditional-effects",
    Forall: ":conditional-effects",
    Decrease: ":numeric-fluents",
    Assign: ":numeric-fluents",
    ScaleUp: ":numeric-fluents",
    ScaleDown: ":numeric-fluents",
}
"""The requirement each construct beyond STRIPS needs, for error messages."""


def fact(name: str, args: Sequence[str] = ()) -> Fact:
    """A ground atom in PDDL syntax: ``fact("at", ["home"]) == "(at home)"``."""
    return "(" + " ".join([name, *args]) + ")"


def _unsupported(where: str, formula: object) -> PDDLError:
    needs = _NEEDS.get(type(formula), f"a {type(formula).__name__} construct")
    return PDDLError(
        f"{where}: {formula} needs {needs}, which the planner does not support "
        f"(supported: {SUPPORTED})"
    )


def _conjuncts(formula: Formula | None) -> list[Formula]:
    if formula is None:
        return []
    if isinstance(formula, And):
        return [part for operand in formula.operands for part in _conjuncts(operand)]
    return [formula]


def _term_names(terms: Sequence[Variable | Constant]) -> tuple[str, ...]:
    """Variables as ``?name``, objects by name."""
    return tuple(f"?{t.name}" if isinstance(t, Variable) else str(t.name) for t in terms)


@dataclass(frozen=True)
class _Atom:
    """A lifted atom: predicate name and terms (``?var`` or object names)."""

    name: str
    terms: tuple[str, ...]

    def ground(self, binding: Mapping[str, str]) -> Fact:
        return fact(self.name, [binding.get(t, t) for t in self.terms])


def _atom(formula: object, where: str) -> _Atom:
    if not isinstance(formula, Predicate):
        raise _unsupported(where, formula)
    return _Atom(formula.name, _term_names(formula.terms))


@dataclass(frozen=True)
class _Schema:
    """An action schema split into STRIPS parts."""

    name: str
    parameters: tuple[tuple[str, frozenset[str]], ...]  # ("?x", type tags)
    pre: tuple[_Atom, ...]
    add: tuple[_Atom, ...]
    delete: tuple[_Atom, ...]
    cost: int


def _cost(effect: Increase, where: str) -> int:
    target, amount = effect.operands
    if not isinstance(target, NumericFunction) or target.name != TOTAL_COST:
        raise PDDLError(f"{where}: only (increase (total-cost) n) is supported, got {effect}")
    value = amount.value if isinstance(amount, NumericValue) else -1
    if value < 0 or value != int(value):
        raise PDDLError(f"{where}: action cost {amount} is not a non-negative integer")
    return int(value)


def _schema(action: Action) -> _Schema:
    where = f"action {action.name!r}"
    add, delete = [], []
    cost = 0  # Fast Downward: an action without (increase (total-cost) n) costs 0
    for effect in _conjuncts(action.effect):
        if isinstance(effect, Increase):
            cost = _cost(effect, where)
        elif isinstance(effect, Not):
            delete.append(_atom(effect.argument, f"{where} effect"))
        else:
            add.append(_atom(effect, f"{where} effect"))
    return _Schema(
        name=action.name,
        parameters=tuple(
            (f"?{p.name}", frozenset(map(str, p.type_tags))) for p in action.parameters
        ),
        pre=tuple(_atom(f, f"{where} precondition") for f in _conjuncts(action.precondition)),
        add=tuple(add),
        delete=tuple(delete),
        cost=cost,
    )


def _check_support(domain: Domain, problem: Problem) -> None:
    requirements = set(domain.requirements) | set(problem.requirements or ())
    unsupported = sorted(str(r) for r in requirements - SUPPORTED_REQUIREMENTS)
    if unsupported:
        raise PDDLError(
            f"domain {domain.name!r}: requirement(s) {' '.join(unsupported)} not supported "
            f"by the planner (supported: {SUPPORTED})"
        )
    if domain.derived_predicates:
        raise PDDLError(f"domain {domain.name!r}: derived predicates are not supported")
    if problem.domain_name != domain.name:
        raise PDDLError(
            f"problem {problem.name!r} is for domain {problem.domain_name!r}, not {domain.name!r}"
        )
    metric = problem.metric
    if metric is not None and (
        metric.optimization != "minimize" or str(metric.expression) != f"({TOTAL_COST})"
    ):
        raise PDDLError(
            f"problem {problem.name!r}: only (:metric minimize (total-cost)) is supported, "
            f"got {metric}"
        )


def _objects_by_type(domain: Domain, problem: Problem) -> dict[str, set[str]]:
    """Every type's objects, subtypes' objects included (``object`` holds all)."""
    parents = {str(k): (str(v) if v is not None else OBJECT) for k, v in domain.types.items()}
    by_type: dict[str, set[str]] = {OBJECT: set(), **{t: set() for t in parents}}
    objects: set[Constant] = {*domain.constants, *problem.objects}
    for obj in objects:
        kind = str(obj.type_tag) if obj.type_tag is not None else OBJECT
        if kind not in by_type:
            raise PDDLError(f"object {obj.name!r} has undeclared type {kind!r}")
        seen = set()
        while kind not in seen:  # up to `object`; `seen` guards against type cycles
            seen.add(kind)
            by_type[kind].add(str(obj.name))
            kind = parents.get(kind, OBJECT)
    return by_type


def _initial_state(problem: Problem) -> frozenset[Fact]:
    """The init's facts (a ``(= (total-cost) 0)`` is allowed and ignored)."""
    facts = set()
    for item in problem.init:
        if isinstance(item, EqualTo) and str(item.operands[0]) == f"({TOTAL_COST})":
            continue
        facts.add(_atom(item, "init").ground({}))
    return frozenset(facts)


def _unify(
    terms: Sequence[str],
    args: Sequence[str],
    binding: dict[str, str],
    candidates: Mapping[str, set[str]],
) -> dict[str, str] | None:
    if len(terms) != len(args):
        return None
    extended = dict(binding)
    for term, arg in zip(terms, args, strict=True):
        if term.startswith("?"):
            if extended.setdefault(term, arg) != arg or arg not in candidates.get(term, ()):
                return None
        elif term != arg:
            return None
    return extended


def _product(
    free: Sequence[str], candidates: Mapping[str, set[str]], binding: dict[str, str]
) -> Iterator[dict[str, str]]:
    if not free:
        yield binding
        return
    for obj in sorted(candidates[free[0]]):
        yield from _product(free[1:], candidates, {**binding, free[0]: obj})


def _bindings(
    schema: _Schema,
    static: frozenset[str],
    init_args: Mapping[str, list[tuple[str, ...]]],
    objects_by_type: Mapping[str, set[str]],
) -> Iterator[dict[str, str]]:
    """Type-correct parameter bindings that satisfy the static preconditions.

    Static atoms (predicates no action changes) are matched against the init first, so
    only their consistent bindings are enumerated; the remaining parameters range over
    their types' objects.
    """
    candidates = {
        var: set().union(*(objects_by_type.get(t, set()) for t in tags))
        if tags
        else objects_by_type[OBJECT]
        for var, tags in schema.parameters
    }
    static_atoms = [atom for atom in schema.pre if atom.name in static]

    def match(i: int, binding: dict[str, str]) -> Iterator[dict[str, str]]:
        if i == len(static_atoms):
            free = [var for var, _ in schema.parameters if var not in binding]
            yield from _product(free, candidates, binding)
            return
        for args in init_args.get(static_atoms[i].name, ()):
            extended = _unify(static_atoms[i].terms, args, binding, candidates)
            if extended is not None:
                yield from match(i + 1, extended)

    yield from match(0, {})


def _relaxed_reachable(
    init: frozenset[Fact], operators: Sequence[Operator]
) -> tuple[list[Operator], frozenset[Fact]]:
    """Operators and facts reachable when delete effects are ignored (linear-time fixpoint)."""
    waiting = [len(op.pre) for op in operators]
    users: dict[Fact, list[int]] = {}
    for i, op in enumerate(operators):
        for f in op.pre:
            users.setdefault(f, []).append(i)
    reached = set(init)
    queue = deque(init)

    def fire(i: int) -> None:
        for f in operators[i].add - reached:
            reached.add(f)
            queue.append(f)

    for i, count in enumerate(waiting):
        if count == 0:
            fire(i)
    while queue:
        for i in users.get(queue.popleft(), ()):
            waiting[i] -= 1
            if waiting[i] == 0:
                fire(i)
    usable = [op for i, op in enumerate(operators) if waiting[i] == 0]
    return usable, frozenset(reached)


def ground(domain: Domain, problem: Problem) -> Task:
    """Ground every action over the typed objects and keep the relaxed-reachable operators.

    Costs follow Fast Downward: with ``(:metric minimize (total-cost))`` an operator costs its
    ``(increase (total-cost) n)`` (0 without one); without a metric every operator costs 1.
    (The ``pddl`` parser only accepts constant costs here: function-valued costs need
    ``:numeric-fluents``.)
    Ground operators are named ``action arg1 arg2`` (just ``action`` without parameters).

    Args:
        domain: the parsed domain.
        problem: the parsed problem.

    Returns:
        The ground task.

    Raises:
        PDDLError: an unsupported requirement or construct (the requirement named), an
            undeclared type, a problem for another domain, a metric other than minimising
            total-cost, or a cost that is not a non-negative integer constant.
    """
    _check_support(domain, problem)
    objects_by_type = _objects_by_type(domain, problem)
    init = _initial_state(problem)
    goal = frozenset(_atom(f, "goal").ground({}) for f in _conjuncts(problem.goal))
    schemas = [_schema(action) for action in sorted(domain.actions, key=lambda a: a.name)]
    changed = {atom.name for s in schemas for atom in (*s.add, *s.delete)}
    static = frozenset(p.name for p in domain.predicates) - changed
    init_args: dict[str, list[tuple[str, ...]]] = {}
    for f in sorted(init):
        name, *args = f[1:-1].split(" ")
        init_args.setdefault(name, []).append(tuple(args))
    operators = [
        Operator(
            name=" ".join([schema.name, *(binding[var] for var, _ in schema.parameters)]),
            pre=frozenset(a.ground(binding) for a in schema.pre),
            add=frozenset(a.ground(binding) for a in schema.add),
            delete=frozenset(a.ground(binding) for a in schema.delete),
            cost=schema.cost if problem.metric is not None else 1,
        )
        for schema in schemas
        for binding in _bindings(schema, static, init_args, objects_by_type)
    ]
    usable, reachable = _relaxed_reachable(init, operators)
    return Task(problem.name, init, goal, tuple(usable), reachable)
