"""Ground STRIPS tasks and plan results: the data the searches and backends exchange."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass
from functools import cached_property
from typing import Any

from osg_control.errors import PlanningError

Fact = str
"""A ground atom in PDDL syntax, e.g. ``(at home)`` or ``(door-open)``."""
State = frozenset[Fact]


@dataclass(frozen=True)
class Operator:
    """A ground action: applicable when ``pre <= state`` and no ``pre_neg`` fact holds;
    leads to ``(state - delete) | add``."""

    name: str
    pre: frozenset[Fact]
    add: frozenset[Fact]
    delete: frozenset[Fact]
    cost: int
    pre_neg: frozenset[Fact] = frozenset()

    def applicable(self, state: State) -> bool:
        """Whether every precondition holds in ``state`` (and no negated one)."""
        return self.pre <= state and self.pre_neg.isdisjoint(state)

    def apply(self, state: State) -> State:
        """The successor state (delete first, then add, as in PDDL)."""
        return (state - self.delete) | self.add


@dataclass(frozen=True)
class Task:
    """A ground planning task.

    Attributes:
        name: the problem name.
        init: the facts true initially (all others false).
        goal: the facts that must hold at the end.
        operators: the ground operators reachable in the delete relaxation.
        reachable: every fact reachable in the delete relaxation (a superset of what any
            plan can reach).
        goal_neg: the facts that must be false at the end.
    """

    name: str
    init: State
    goal: frozenset[Fact]
    operators: tuple[Operator, ...]
    reachable: frozenset[Fact]
    goal_neg: frozenset[Fact] = frozenset()

    def is_goal(self, state: State) -> bool:
        """Whether ``state`` satisfies the goal."""
        return self.goal <= state and self.goal_neg.isdisjoint(state)

    @cached_property
    def _by_name(self) -> dict[str, Operator]:
        return {op.name: op for op in self.operators}

    def operator(self, name: str) -> Operator:
        """Look an operator up by its name (``action arg1 arg2``).

        Raises:
            PlanningError: no such ground operator.
        """
        try:
            return self._by_name[name]
        except KeyError:
            raise PlanningError(
                f"task {self.name!r} has no (reachable) operator {name!r}"
            ) from None

    def simulate(self, names: Iterable[str]) -> State:
        """Apply operators by name from ``init``, checking each is applicable.

        Args:
            names: operator names in plan order.

        Returns:
            The final state.

        Raises:
            PlanningError: an unknown operator, or one whose preconditions fail (listed).
        """
        state = self.init
        for step, name in enumerate(names, start=1):
            op = self.operator(name)
            if not op.applicable(state):
                missing = " ".join(
                    sorted(op.pre - state) + [f"(not {f})" for f in sorted(op.pre_neg & state)]
                )
                raise PlanningError(f"step {step} ({name}): preconditions {missing} do not hold")
            state = op.apply(state)
        return state


@dataclass(frozen=True)
class PlanStep:
    """One operator of a plan and its cost."""

    action: str
    cost: int


MAX_TIME_S = 1e6
"""The longest search time limit [s] (about 11.6 days): Fast Downward overflowed at 1e308."""
MAX_STATES = 2**31 - 1
"""The most states a search may keep (a 32-bit count)."""


@dataclass(frozen=True)
class SearchLimits:
    """Bounds on a search; reaching one gives the answer "unknown", never "no plan".

    Attributes:
        time_s: wall-clock seconds in [0, ``MAX_TIME_S``] (0: answer "unknown" at once),
            or None for no bound.
        max_states: states kept in memory (the built-in search) in [1, ``MAX_STATES``], or
            None for no bound.

    Raises:
        ValueError: a bound outside its range (NaN, inf, a bool or a string included).
    """

    time_s: float | None = None
    max_states: int | None = None

    def __post_init__(self) -> None:
        time_s, states = self.time_s, self.max_states
        if time_s is not None and not (
            isinstance(time_s, int | float)
            and not isinstance(time_s, bool)
            and 0 <= time_s <= MAX_TIME_S
        ):
            raise ValueError(f"time limit must be in [0, {MAX_TIME_S:g}] s, got {time_s!r}")
        if states is not None and not (
            isinstance(states, int) and not isinstance(states, bool) and 1 <= states <= MAX_STATES
        ):
            raise ValueError(f"max_states must be in [1, {MAX_STATES}], got {states!r}")


NO_LIMITS = SearchLimits()
"""An unbounded search."""


@dataclass(frozen=True)
class SearchStats:
    """Search effort: states expanded and generated, and seconds spent."""

    expanded: int
    generated: int
    time_s: float


@dataclass(frozen=True)
class PlanResult:
    """A planner's answer.

    Attributes:
        planner: the planner's registry name.
        task: the problem name.
        goal: the goal facts.
        steps: the plan, or None when there is none.
        stats: search effort.
        unreached: when there is no plan: the goal facts unreachable even in the delete
            relaxation, or, if all of them are reachable there, every goal fact unmet initially.
        limit: when the search stopped at a limit (the answer is then "unknown"): which.
    """

    planner: str
    task: str
    goal: tuple[Fact, ...]
    steps: tuple[PlanStep, ...] | None
    stats: SearchStats
    unreached: tuple[Fact, ...] = ()
    limit: str | None = None

    @property
    def solved(self) -> bool:
        """Whether a plan was found."""
        return self.steps is not None

    @property
    def status(self) -> str:
        """``solved``, ``unsolvable`` (proved: a complete search ran out) or ``unknown``."""
        if self.steps is not None:
            return "solved"
        return "unknown" if self.limit is not None else "unsolvable"

    @property
    def cost(self) -> int | None:
        """The plan's total cost (None without a plan)."""
        return None if self.steps is None else sum(step.cost for step in self.steps)

    @property
    def actions(self) -> tuple[str, ...]:
        """The plan's operator names (empty without a plan)."""
        return tuple(step.action for step in self.steps or ())

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary, with ``solved`` and ``cost`` spelled out."""
        return {**asdict(self), "solved": self.solved, "status": self.status, "cost": self.cost}


def goal_literals(task: Task) -> tuple[str, ...]:
    """The goal as literals: its facts, then ``(not fact)`` for each negative goal."""
    return (*sorted(task.goal), *(f"(not {f})" for f in sorted(task.goal_neg)))


def no_plan(planner: str, task: Task, stats: SearchStats) -> PlanResult:
    """The "no plan" answer, naming the goal facts that stay unreached."""
    unreached = task.goal - task.reachable or task.goal - task.init
    return PlanResult(
        planner, task.name, goal_literals(task), None, stats, tuple(sorted(unreached))
    )


def unknown(planner: str, task: Task, stats: SearchStats, limit: str) -> PlanResult:
    """The "unknown" answer of a search stopped by ``limit`` (e.g. ``time limit 10 s``)."""
    return PlanResult(planner, task.name, goal_literals(task), None, stats, limit=limit)


def plan_result(planner: str, task: Task, names: Sequence[str], stats: SearchStats) -> PlanResult:
    """A solved answer: look each step's cost up and check the plan reaches the goal.

    Raises:
        PlanningError: the plan is not executable or misses goal facts (a backend bug).
    """
    final = task.simulate(names)
    if not task.is_goal(final):
        missing = " ".join(
            sorted(task.goal - final) + [f"(not {f})" for f in sorted(task.goal_neg & final)]
        )
        raise PlanningError(f"{planner}: plan for {task.name!r} does not reach {missing}")
    steps = tuple(PlanStep(name, task.operator(name).cost) for name in names)
    return PlanResult(planner, task.name, goal_literals(task), steps, stats)
