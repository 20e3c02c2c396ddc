"""Ground a parsed domain/problem pair into a ``Task``.

Supported: STRIPS, typing, negative preconditions and goals, equality, and action costs
(constants or static numeric functions). Anything else (disjunctive or quantified
preconditions, conditional effects, derived predicates, numeric fluents) is rejected with a
``PDDLError`` that names the requirement, so no task is ever silently mis-read. Files are
checked with lines before (``planning.reader``); this covers domains built in code too.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, replace

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

from osg_control.errors import PDDLError
from osg_control.planning.task import Fact, Operator, Task

SUPPORTED = ":strips :typing :negative-preconditions :equality :action-costs"
TOTAL_COST = "total-cost"
OBJECT = "object"

_NEEDS: dict[type, str] = {
    Or: ":disjunctive-preconditions",
    Imply: ":disjunctive-preconditions",
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


def norm(name: object) -> str:
    """A PDDL name in its normal form (lower case): names are case-insensitive."""
    return str(name).lower()


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
    """Variables as ``?name``, objects by name (normal form)."""
    return tuple(f"?{norm(t.name)}" if isinstance(t, Variable) else norm(t.name) for t in terms)


@dataclass(frozen=True)
class _Atom:
    """A lifted atom: predicate (or function) name and terms (``?var`` or object names)."""

    name: str
    terms: tuple[str, ...]

    def args(self, binding: Mapping[str, str]) -> tuple[str, ...]:
        """The terms with the variables replaced by their objects."""
        return tuple(binding.get(t, t) for t in self.terms)

    def ground(self, binding: Mapping[str, str]) -> Fact:
        """The ground fact under ``binding``."""
        return fact(self.name, self.args(binding))


def _atom(formula: object, where: str) -> _Atom:
    if isinstance(formula, Predicate):
        return _Atom(norm(formula.name), _term_names(formula.terms))
    if isinstance(formula, EqualityAtom):
        return _Atom("=", _term_names([formula.left, formula.right]))
    raise _unsupported(where, formula)


def _literals(formula: Formula | None, where: str) -> tuple[list[_Atom], list[_Atom]]:
    """A conjunction of literals as its positive and its negative atoms."""
    positive, negative = [], []
    for part in _conjuncts(formula):
        if isinstance(part, Not):
            negative.append(_atom(part.argument, where))
        else:
            positive.append(_atom(part, where))
    return positive, negative


Cost = int | _Atom
"""An action's cost: a constant, or a static numeric function term looked up in the init."""


@dataclass(frozen=True)
class _Schema:
    """An action schema split into STRIPS parts."""

    name: str
    parameters: tuple[tuple[str, frozenset[str]], ...]  # ("?x", type tags)
    pre: tuple[_Atom, ...]
    pre_neg: tuple[_Atom, ...]
    add: tuple[_Atom, ...]
    delete: tuple[_Atom, ...]
    cost: Cost


def _integer_cost(value: float | None) -> int | None:
    """``value`` as an action cost (a finite non-negative integer), else None."""
    if value is None or not math.isfinite(value) or value < 0 or value != int(value):
        return None
    return int(value)


def _cost(effect: Increase, where: str) -> Cost:
    target, amount = effect.operands
    if not isinstance(target, NumericFunction) or norm(target.name) != TOTAL_COST:
        raise PDDLError(f"{where}: only (increase (total-cost) n) is supported, got {effect}")
    if isinstance(amount, NumericFunction):
        return _Atom(norm(amount.name), _term_names(amount.terms))
    value = _integer_cost(amount.value if isinstance(amount, NumericValue) else None)
    if value is None:
        raise PDDLError(f"{where}: action cost {amount} is not a non-negative integer")
    return value


def _schema(action: Action) -> _Schema:
    where = f"action {action.name!r}"
    add, delete = [], []
    cost: Cost = 0  # Fast Downward: an action without (increase (total-cost) n) costs 0
    for effect in _conjuncts(action.effect):
        if isinstance(effect, Increase):
            cost = _cost(effect, where)
        elif isinstance(effect, Not):
            delete.append(_atom(effect.argument, f"{where} effect"))
        elif isinstance(effect, Predicate):
            add.append(_atom(effect, f"{where} effect"))
        else:
            raise _unsupported(f"{where} effect", effect)
    pre, pre_neg = _literals(action.precondition, f"{where} precondition")
    return _Schema(
        name=norm(action.name),
        parameters=tuple(
            (f"?{norm(p.name)}", frozenset(map(norm, p.type_tags))) for p in action.parameters
        ),
        pre=tuple(pre),
        pre_neg=tuple(pre_neg),
        add=tuple(add),
        delete=tuple(delete),
        cost=cost,
    )


def _check_support(domain: Domain, problem: Problem) -> None:
    if domain.derived_predicates:
        raise PDDLError(
            f"domain {domain.name!r}: derived predicates need :derived-predicates, which the "
            f"planner does not support (supported: {SUPPORTED})"
        )
    if norm(problem.domain_name) != norm(domain.name):
        raise PDDLError(
            f"problem {problem.name!r} is for domain {problem.domain_name!r}, not {domain.name!r}"
        )
    metric = problem.metric
    if metric is not None and (
        metric.optimization != "minimize" or norm(metric.expression) != f"({TOTAL_COST})"
    ):
        raise PDDLError(
            f"problem {problem.name!r}: only (:metric minimize (total-cost)) is supported, "
            f"got {metric}"
        )


def _objects_by_type(domain: Domain, problem: Problem) -> dict[str, set[str]]:
    """Every type's objects, subtypes' objects included (``object`` holds all)."""
    parents = {norm(k): (norm(v) if v is not None else OBJECT) for k, v in domain.types.items()}
    by_type: dict[str, set[str]] = {OBJECT: set(), **{t: set() for t in parents}}
    objects: set[Constant] = {*domain.constants, *problem.objects}
    for obj in objects:
        kind = norm(obj.type_tag) if obj.type_tag is not None else OBJECT
        if kind not in by_type:
            raise PDDLError(f"object {obj.name!r} has undeclared type {kind!r}")
        seen = set()
        while kind not in seen:  # up to `object`; `seen` guards against type cycles
            seen.add(kind)
            by_type[kind].add(norm(obj.name))
            kind = parents.get(kind, OBJECT)
    return by_type


def _initial_state(problem: Problem) -> tuple[frozenset[Fact], dict[Fact, float]]:
    """The init's facts, and the values of its numeric functions by ground term."""
    facts, values = set(), {}
    for item in problem.init:
        if isinstance(item, EqualTo):
            term, value = item.operands
            if not isinstance(term, NumericFunction) or not isinstance(value, NumericValue):
                raise PDDLError(
                    f"init: only (= (function objects) number) is supported, got {item}"
                )
            values[fact(norm(term.name), _term_names(term.terms))] = value.value
        else:
            facts.add(_atom(item, "init").ground({}))
    return frozenset(facts), values


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
    their types' objects. Equalities and negated static atoms then filter the bindings.
    """
    candidates = {
        var: set().union(*(objects_by_type.get(t, set()) for t in tags))
        if tags
        else objects_by_type[OBJECT]
        for var, tags in schema.parameters
    }
    static_atoms = [atom for atom in schema.pre if atom.name in static]
    equal = [atom for atom in schema.pre if atom.name == "="]
    unequal = [atom for atom in schema.pre_neg if atom.name == "="]
    absent = [atom for atom in schema.pre_neg if atom.name in static]
    init_sets = {name: set(args) for name, args in init_args.items()}

    def admissible(binding: dict[str, str]) -> bool:
        return (
            all(len(set(a.args(binding))) == 1 for a in equal)
            and all(len(set(a.args(binding))) == 2 for a in unequal)
            and not any(a.args(binding) in init_sets.get(a.name, ()) for a in absent)
        )

    def match(i: int, binding: dict[str, str]) -> Iterator[dict[str, str]]:
        if i == len(static_atoms):
            free = [var for var, _ in schema.parameters if var not in binding]
            yield from (b for b in _product(free, candidates, binding) if admissible(b))
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


def _operator_cost(
    schema: _Schema, binding: Mapping[str, str], values: Mapping[Fact, float]
) -> int:
    """The cost of a ground action: its constant, or its function term's init value."""
    if isinstance(schema.cost, int):
        return schema.cost
    term = schema.cost.ground(binding)
    value = values.get(term)
    cost = _integer_cost(value)
    if cost is None:
        got = "no value in :init" if value is None else f"value {value}"
        raise PDDLError(
            f"action {schema.name!r}: cost {term} has {got}; an action cost must be a "
            "non-negative integer"
        )
    return cost


def ground(domain: Domain, problem: Problem) -> Task:
    """Ground every action over the typed objects and keep the relaxed-reachable operators.

    Names are compared in normal form (lower case). Costs follow Fast Downward: with
    ``(:metric minimize (total-cost))`` an operator costs its ``(increase (total-cost) c)``
    (0 without one), ``c`` a constant or a static function term whose value the problem's
    init gives; without a metric every operator costs 1. Static preconditions (positive,
    negative, equalities) are decided here; the remaining negative preconditions and goals
    stay on the operators and the task. The relaxed reachability ignores negative
    preconditions, so it over-approximates: an operator it drops can never be applied.
    Ground operators are named ``action arg1 arg2`` (just ``action`` without parameters).

    Args:
        domain: the parsed domain.
        problem: the parsed problem.

    Returns:
        The ground task.

    Raises:
        PDDLError: an unsupported construct (the requirement named), an undeclared type, a
            problem for another domain, a metric other than minimising total-cost, or a
            reachable action whose cost is not a non-negative integer.
    """
    _check_support(domain, problem)
    objects_by_type = _objects_by_type(domain, problem)
    init, values = _initial_state(problem)
    goal, goal_neg = _literals(problem.goal, "goal")
    schemas = [_schema(action) for action in sorted(domain.actions, key=lambda a: norm(a.name))]
    changed = {atom.name for s in schemas for atom in (*s.add, *s.delete)}
    static = frozenset(norm(p.name) for p in domain.predicates) - changed
    init_args: dict[str, list[tuple[str, ...]]] = {}
    for f in sorted(init):
        name, *args = f[1:-1].split(" ")
        init_args.setdefault(name, []).append(tuple(args))
    ground_ops = [
        (
            schema,
            binding,
            Operator(
                name=" ".join([schema.name, *(binding[var] for var, _ in schema.parameters)]),
                pre=frozenset(a.ground(binding) for a in schema.pre if a.name != "="),
                add=frozenset(a.ground(binding) for a in schema.add),
                delete=frozenset(a.ground(binding) for a in schema.delete),
                cost=0,
                pre_neg=frozenset(
                    a.ground(binding)
                    for a in schema.pre_neg
                    if a.name != "=" and a.name not in static
                ),
            ),
        )
        for schema in schemas
        for binding in _bindings(schema, static, init_args, objects_by_type)
    ]
    usable, reachable = _relaxed_reachable(init, [op for _, _, op in ground_ops])
    kept = {id(op) for op in usable}
    operators = tuple(
        replace(op, cost=_operator_cost(schema, binding, values) if problem.metric else 1)
        for schema, binding, op in ground_ops
        if id(op) in kept
    )
    return Task(
        problem.name,
        init,
        frozenset(a.ground({}) for a in goal),
        operators,
        reachable,
        frozenset(a.ground({}) for a in goal_neg),
    )
