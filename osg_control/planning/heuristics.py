"""Admissible heuristics for the ground tasks: h_max (delete relaxation) and the blind one."""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable

from osg_control.planning.task import Fact, State, Task

Heuristic = Callable[[State], float]
"""Estimated cost from a state to the goal; ``math.inf`` marks a dead end."""


def blind(state: State) -> float:
    """Zero everywhere: turns A* into uniform-cost search (Dijkstra)."""
    return 0.0


class HMax:
    """h_max: the cost of the dearest goal fact when every fact costs its dearest precondition.

    Computed by a generalised Dijkstra over the delete relaxation that stops as soon as the
    last goal fact is settled. Admissible and consistent, so A* with it is optimal.
    """

    def __init__(self, task: Task) -> None:
        """Index the task's operators by precondition fact.

        Args:
            task: the ground task.
        """
        self._goal = task.goal
        self._ops = task.operators
        self._pre_count = [len(op.pre) for op in task.operators]
        self._users: dict[Fact, list[int]] = {}
        for i, op in enumerate(task.operators):
            for f in op.pre:
                self._users.setdefault(f, []).append(i)

    def __call__(self, state: State) -> float:
        """The h_max value of ``state`` (``math.inf`` when a goal fact is relaxed-unreachable).

        Args:
            state: the state to evaluate.

        Returns:
            The estimate.
        """
        goals_left = len(self._goal - state)
        if goals_left == 0:
            return 0.0
        settled: set[Fact] = set(state)
        waiting = self._pre_count.copy()
        for f in state:
            for i in self._users.get(f, ()):
                waiting[i] -= 1
        heap: list[tuple[float, Fact]] = []
        cost = 0.0
        ready = [i for i, count in enumerate(waiting) if count == 0]
        while True:
            for i in ready:
                op = self._ops[i]
                for f in op.add:
                    if f not in settled:
                        heapq.heappush(heap, (cost + op.cost, f))
            ready = []
            while heap and heap[0][1] in settled:
                heapq.heappop(heap)
            if not heap:
                return math.inf
            cost, f = heapq.heappop(heap)
            settled.add(f)
            if f in self._goal:
                goals_left -= 1
                if goals_left == 0:
                    return cost
            for i in self._users.get(f, ()):
                waiting[i] -= 1
                if waiting[i] == 0:
                    ready.append(i)
