"""Plans for one skill graph, remembered: an executor asks the same few questions (which
node, which facts, which goal) over and over, across replans and episodes."""

from __future__ import annotations

from collections.abc import Iterable
from functools import lru_cache

from osg_control.domain.base import Domain as OSGDomain
from osg_control.planning.api import plan_for_goal
from osg_control.planning.pddl_io import SkillPDDL
from osg_control.planning.task import PlanResult

PLAN_MEMO_SIZE = 4096
"""Distinct (planner, goal, node, facts) questions kept; the least recently asked go first.
A kitchen evaluation asks a few hundred."""


class PlanMemo:
    """``plan_for_goal`` over one PDDL domain, each question answered once.

    The searches run without limits and the built-in ones are deterministic, so a
    remembered answer is the plan the planner would give again (its ``stats.time_s`` is
    the first search's); ``auto`` hands a search past its time budget to Fast Downward,
    whose optimal plan may break a tie of costs otherwise. The memo holds no world state.

    Args:
        domain: the skill domain (its nodes and facts).
        pddl: the PDDL domain of the skill graph whose costs the plans minimise.
        size: how many answers to keep (``PLAN_MEMO_SIZE``).
    """

    def __init__(self, domain: OSGDomain, pddl: SkillPDDL, size: int = PLAN_MEMO_SIZE) -> None:
        self.domain = domain
        self.pddl = pddl
        self._answer = lru_cache(maxsize=size)(self._search)

    def __call__(
        self, goal: str | Iterable[str], node: str, facts: Iterable[str], planner: str
    ) -> PlanResult:
        """The plan from ``node`` with ``facts`` true (all others false) to ``goal``
        (``plan_for_goal``'s forms: facts, or one string of them)."""
        asked = goal if isinstance(goal, str) else tuple(goal)
        return self._answer(planner, asked, node, tuple(sorted(set(facts))))

    def _search(
        self, planner: str, goal: str | tuple[str, ...], node: str, facts: tuple[str, ...]
    ) -> PlanResult:
        return plan_for_goal(self.domain, goal, node, facts, planner, pddl=self.pddl)

    def asked(self) -> tuple[int, int]:
        """(questions answered from memory, searches run) so far."""
        info = self._answer.cache_info()
        return info.hits, info.misses
