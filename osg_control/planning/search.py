"""Best-first search over ground tasks: A* with an admissible heuristic, and uniform-cost
search (blind A*). Complete: a search that runs out of states proves the task unsolvable; one
stopped by a ``SearchLimits`` bound answers "unknown"."""

from __future__ import annotations

import heapq
import itertools
import math
import time

from osg_control.planning.heuristics import Heuristic
from osg_control.planning.task import (
    NO_LIMITS,
    Fact,
    Operator,
    PlanResult,
    SearchLimits,
    SearchStats,
    State,
    Task,
    no_plan,
    plan_result,
    unknown,
)


class SuccessorGenerator:
    """Finds the operators applicable in a state without testing every operator.

    Each operator is filed under its precondition fact that the fewest operators share; a
    state then only tests the operators filed under its own facts (plus those without
    preconditions).
    """

    def __init__(self, operators: tuple[Operator, ...]) -> None:
        """Index the operators.

        Args:
            operators: the task's ground operators.
        """
        share: dict[Fact, int] = {}
        for op in operators:
            for f in op.pre:
                share[f] = share.get(f, 0) + 1
        self._always: list[Operator] = []  # no positive precondition: tested every time
        self._by_fact: dict[Fact, list[Operator]] = {}
        for op in operators:
            if op.pre:
                key = min(op.pre, key=lambda f: (share[f], f))
                self._by_fact.setdefault(key, []).append(op)
            else:
                self._always.append(op)

    def __call__(self, state: State) -> list[Operator]:
        """The operators applicable in ``state``."""
        found = [op for op in self._always if op.applicable(state)]
        for f in state:
            found += (op for op in self._by_fact.get(f, ()) if op.applicable(state))
        return found


def best_first_search(
    task: Task, heuristic: Heuristic, planner: str, limits: SearchLimits = NO_LIMITS
) -> PlanResult:
    """A* (f = g + h, ties to the lower h, then first in); optimal for an admissible h.

    States are re-opened when reached more cheaply, so optimality holds even for an
    inconsistent heuristic. Dead ends (h = inf) are pruned, which is safe for a heuristic
    that is infinite only on states from which the goal is unreachable.

    Args:
        task: the ground task.
        heuristic: the estimate of the cost to the goal.
        planner: the name recorded in the result.
        limits: time and stored-state bounds.

    Returns:
        The cheapest plan; "no plan" (naming the unreached goal facts) when the search ran
        out of states; "unknown" when it reached a limit first.
    """
    start = time.perf_counter()
    deadline = start + limits.time_s if limits.time_s is not None else math.inf
    max_states = limits.max_states if limits.max_states is not None else math.inf
    successors = SuccessorGenerator(task.operators)
    best_g: dict[State, int] = {task.init: 0}
    parent: dict[State, tuple[State, Operator]] = {}
    h_cache: dict[State, float] = {task.init: heuristic(task.init)}
    tie = itertools.count()
    open_list = [(h_cache[task.init], h_cache[task.init], next(tie), 0, task.init)]
    expanded = generated = 0
    while open_list and open_list[0][0] < math.inf:
        _, _, _, g, state = heapq.heappop(open_list)
        if g > best_g[state]:
            continue  # a stale entry: the state was reached more cheaply since
        if task.is_goal(state):
            names = []
            while state in parent:
                state, op = parent[state]
                names.append(op.name)
            stats = SearchStats(expanded, generated, time.perf_counter() - start)
            return plan_result(planner, task, names[::-1], stats)
        expanded += 1
        if time.perf_counter() > deadline:
            stats = SearchStats(expanded, generated, time.perf_counter() - start)
            return unknown(planner, task, stats, f"time limit {limits.time_s:g} s")
        if len(best_g) > max_states:
            stats = SearchStats(expanded, generated, time.perf_counter() - start)
            return unknown(planner, task, stats, f"state limit {limits.max_states}")
        for op in successors(state):
            succ = op.apply(state)
            generated += 1
            succ_g = g + op.cost
            if succ_g >= best_g.get(succ, math.inf):
                continue
            h = h_cache.get(succ)
            if h is None:
                h = h_cache[succ] = heuristic(succ)
            if h == math.inf:
                continue
            best_g[succ] = succ_g
            parent[succ] = (state, op)
            heapq.heappush(open_list, (succ_g + h, h, next(tie), succ_g, succ))
    return no_plan(planner, task, SearchStats(expanded, generated, time.perf_counter() - start))
