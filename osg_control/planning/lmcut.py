"""The LM-cut heuristic (Helmert & Domshlak, ICAPS 2009), written from the paper.

Each round computes h_max in the delete relaxation under the current (reduced) costs,
chooses for every operator its dearest precondition (the precondition choice function),
and cuts the justification graph between the facts reachable from the state and the goal
zone (the facts that reach the goal through zero-cost edges). The cheapest operator of the
cut is a disjunctive action landmark: its cost is added to the estimate and subtracted from
every operator of the cut. Rounds stop when the goal's h_max is 0. The sum is admissible
and dominates h_max. Negative preconditions and goals are ignored (a relaxation too).
"""

from __future__ import annotations

import heapq
import math

from osg_control.planning.task import State, Task

_INF = math.inf


class LMCut:
    """LM-cut over a ground task, with facts and operators numbered once."""

    def __init__(self, task: Task) -> None:
        """Number the facts and build the relaxed operators.

        Two artificial facts make every operator and the goal uniform: ``init`` (true in
        every state; the precondition of operators without one) and ``goal`` (added by a
        zero-cost operator whose preconditions are the goal facts).

        Args:
            task: the ground task.
        """
        facts = sorted(set(task.reachable) | set(task.goal) | set(task.init))
        self._index = {f: i for i, f in enumerate(facts)}
        self._init = len(facts)
        self._goal = len(facts) + 1
        self._goal_facts = task.goal
        self._pre: list[list[int]] = []
        self._add: list[list[int]] = []
        self._cost: list[float] = []
        for op in task.operators:
            self._pre.append([self._index[f] for f in op.pre] or [self._init])
            self._add.append([self._index[f] for f in op.add])
            self._cost.append(float(op.cost))
        self._pre.append([self._index[f] for f in task.goal] or [self._init])
        self._add.append([self._goal])
        self._cost.append(0.0)
        self._users: list[list[int]] = [[] for _ in range(len(facts) + 2)]
        self._achievers: list[list[int]] = [[] for _ in range(len(facts) + 2)]
        for o, (pre, add) in enumerate(zip(self._pre, self._add, strict=True)):
            for p in pre:
                self._users[p].append(o)
            for e in add:
                self._achievers[e].append(o)

    def _hmax(self, start: list[int], cost: list[float]) -> tuple[list[float], list[int]]:
        """h_max of every fact from ``start``, and each operator's dearest precondition."""
        hmax = [_INF] * (self._goal + 1)
        unmet = [len(pre) for pre in self._pre]
        choice = [-1] * len(self._pre)
        heap = []
        for f in start:
            hmax[f] = 0.0
            heap.append((0.0, f))
        heapq.heapify(heap)
        while heap:
            value, f = heapq.heappop(heap)
            if value > hmax[f]:
                continue
            for o in self._users[f]:
                unmet[o] -= 1
                if unmet[o] == 0:
                    choice[o] = f  # settled last, so the dearest precondition
                    reached = value + cost[o]
                    for e in self._add[o]:
                        if reached < hmax[e]:
                            hmax[e] = reached
                            heapq.heappush(heap, (reached, e))
        return hmax, choice

    def __call__(self, state: State) -> float:
        """The LM-cut estimate of ``state`` (``math.inf`` when the goal is relaxed-unreachable).

        Args:
            state: the state to evaluate.

        Returns:
            The sum of the cut costs.
        """
        if self._goal_facts <= state:
            return 0.0
        start = [self._index[f] for f in state if f in self._index]
        start.append(self._init)
        cost = self._cost.copy()
        total = 0.0
        while True:
            hmax, choice = self._hmax(start, cost)
            if hmax[self._goal] == _INF:
                return _INF
            if hmax[self._goal] == 0:
                return total
            zone = self._goal_zone(choice, cost)
            cut = self._cut(start, choice, zone)
            least = min(cost[o] for o in cut)
            total += least
            for o in cut:
                cost[o] -= least

    def _goal_zone(self, choice: list[int], cost: list[float]) -> set[int]:
        """Facts from which the goal is reached through zero-cost justification edges."""
        zone = {self._goal}
        stack = [self._goal]
        while stack:
            e = stack.pop()
            for o in self._achievers[e]:
                p = choice[o]
                if p >= 0 and cost[o] == 0 and p not in zone:
                    zone.add(p)
                    stack.append(p)
        return zone

    def _cut(self, start: list[int], choice: list[int], zone: set[int]) -> set[int]:
        """Operators leading from the facts reachable outside the goal zone into it."""
        by_choice: dict[int, list[int]] = {}
        for o, p in enumerate(choice):
            if p >= 0:
                by_choice.setdefault(p, []).append(o)
        seen = set(start)
        stack = list(start)
        cut = set()
        while stack:
            f = stack.pop()
            for o in by_choice.get(f, ()):
                for e in self._add[o]:
                    if e in zone:
                        cut.add(o)
                    elif e not in seen:
                        seen.add(e)
                        stack.append(e)
        return cut
