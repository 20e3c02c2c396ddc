"""Where a start off the skill graph enters it: the manipulation skill whose path the TCP is
on, else (hand empty) a movement skill the classifier scores, chosen by the cost to the goal,
else the applicable skill whose start node is nearest."""

from __future__ import annotations

import numpy as np

from osg_control.classifier.motion import MotionMemory
from osg_control.domain.base import Domain
from osg_control.domain.binding import BoundSkill, bind_step, bindings, end_place
from osg_control.domain.frames import Offsets, node_position, shifted_nodes
from osg_control.domain.spec import nearest_start
from osg_control.execution.locate import recorded_world_holds, skill_on_path
from osg_control.execution.results import EntryClassifier
from osg_control.planning.graph import SkillGraph
from osg_control.planning.memo import PlanMemo
from osg_control.planning.pddl_io import MIN_SUCCESS_RATE, skill_cost

ENTRY_MARGIN = 0.5
"""A movement skill is an entry candidate when its classifier probability is at least this
share of the best one's (``EntryChoice.classify``)."""


class EntryChoice:
    """Chooses the entry skill of a start off the graph.

    Args:
        domain: the domain (its skills, nodes and ``hand_empty`` fact).
        classifier: the state -> movement-skill classifier.
        graph: the cost model (measured success rates and step costs).
        plans: the plans over ``graph`` (a goal-aware choice plans from every candidate).
    """

    def __init__(
        self, domain: Domain, classifier: EntryClassifier, graph: SkillGraph, plans: PlanMemo
    ) -> None:
        self.domain = domain
        self.skills = domain.skills_by_name
        self.classifier = classifier
        self.graph = graph
        self.plans = plans

    def skill(
        self,
        obs: np.ndarray,
        facts: set[str],
        motion: MotionMemory,
        offsets: Offsets | None = None,
        goal: list[str] | None = None,
        planner: str = "astar",
    ) -> str:
        """Off the graph: the manipulation skill whose path the TCP is on; else, the hand
        empty, the classifier's movement skill (``classify``; goal-aware with a ``goal``);
        else the applicable skill whose start node is nearest (retry from where it failed),
        each bound to its objects (``skill obj`` for another than the recorded one, e.g.
        the held cube's). ``motion``: the commands sent so far (the classifier's motion
        input)."""
        on_path = skill_on_path(self.domain, obs, facts, self.skills.values(), offsets)
        if on_path is not None:
            return on_path
        if self.domain.hand_empty in facts:
            return self.classify(obs, facts, motion, goal, planner)
        lifting, offsets = self.domain.lifting, offsets or {}
        bound = [b for s in self.skills.values() for b in bindings(lifting, s)]
        applicable = [b for b in bound if b.skill.preconditions <= facts]
        if not applicable:
            nodes = shifted_nodes(self.domain, offsets)
            return nearest_start(self.skills.values(), nodes, obs[:3]).name

        def distance(b: BoundSkill) -> float:
            start = node_position(self.domain.nodes, b.skill.start, b.offsets(offsets))
            return float(np.linalg.norm(obs[:3] - start))

        nearest = min(applicable, key=distance)  # the first on ties
        return nearest.label if nearest.frames or nearest.facts else nearest.skill.name

    def classify(
        self,
        obs: np.ndarray,
        facts: set[str],
        motion: MotionMemory,
        goal: list[str] | None = None,
        planner: str = "astar",
    ) -> str:
        """The entry movement skill among those whose recorded world holds
        (``recorded_world_holds``; all of them if none does).

        Without a goal: the classifier's likeliest. With one, goal-aware: skills that start
        at the same node share their initiation region, so the classifier splits a start
        there between them; the chance that the state lies in a node's region is the sum of
        its skills' probabilities. Among the skills whose region's chance is at least
        ``ENTRY_MARGIN`` of the best, the one that minimises ``round(-ln P * 1000)`` plus
        its own operator cost plus the plan's cost from its end to the goal (plan costs are
        ``-1000 ln`` of measured success rates: the likeliest way to the goal, entering
        included). A start near home then enters toward the cube for a cube task instead of
        toward the valve and back.
        """
        proba = np.asarray(
            self.classifier.predict_proba(obs, motion.features()), dtype=float
        ).reshape(-1)
        classes = self.classifier.classes
        allowed = np.array([recorded_world_holds(self.skills[c], facts) for c in classes])
        if not allowed.any():
            allowed[:] = True
        scores = np.where(allowed, proba, 0.0)
        if goal is None:
            return classes[int(np.argmax(np.where(allowed, proba, -np.inf)))]
        starts = [self.skills[c].start for c in classes]
        region = np.array([scores[[s == start for s in starts]].sum() for start in starts])
        region = np.where(allowed, region, 0.0)
        candidates = [i for i in range(len(classes)) if region[i] >= ENTRY_MARGIN * region.max()]
        costs = {
            i: self._cost(classes[i], float(region[i]), facts, goal, planner) for i in candidates
        }
        return classes[min(candidates, key=lambda i: (costs[i], -scores[i]))]

    def _cost(
        self, name: str, probability: float, facts: set[str], goal: list[str], planner: str
    ) -> float:
        """``-1000 ln p`` of entering through ``name``, its operator cost and the plan cost
        from its end node, bound to the objects that make it cheapest (inf without a
        plan)."""
        planned, _label, _end, _after = self._cheapest(name, goal, facts, planner)
        if planned == float("inf"):
            return planned
        edge = self.graph.edge(name)
        entering = skill_cost(max(probability, MIN_SUCCESS_RATE)) + skill_cost(edge.success_rate)
        return float(entering + edge.step_cost + planned)

    def bind(
        self, name: str, goal: list[str], facts: set[str], planner: str = "astar"
    ) -> tuple[str, str, set[str]]:
        """The entry skill ``name`` bound to the objects that make the goal cheapest (the
        goal's object: entering toward cube 2 for a goal on cube 2); a skill of one
        binding is its recorded one, without planning; ``skill obj`` (``skill`` found the
        TCP on that bound skill's path) keeps its binding.

        Returns:
            ``(ground operator, where it ends as a planner's start, facts after it)``.
        """
        if " " in name:  # already bound (on a bound skill's path): that binding
            chosen = bind_step(self.domain.lifting, self.skills, name)
            after = (facts - chosen.skill.del_effects) | chosen.skill.add_effects
            return chosen.label, end_place(self.domain.lifting, chosen), after
        _cost, label, end, after = self._cheapest(name, goal, facts, planner, plan_one=False)
        return label, end, after

    def _cheapest(
        self, name: str, goal: list[str], facts: set[str], planner: str, plan_one: bool = True
    ) -> tuple[float, str, str, set[str]]:
        """The binding of skill ``name`` whose end is cheapest to the goal: ``(the plan's
        cost from its end (inf without a plan; 0, unplanned, for a skill of one binding
        unless ``plan_one``), ground operator, end place, facts after it)``; the first on
        ties."""
        best: tuple[float, str, str, set[str]] | None = None
        candidates = bindings(self.domain.lifting, self.skills[name])
        for bound in candidates:
            end = end_place(self.domain.lifting, bound)
            after = (facts - bound.skill.del_effects) | bound.skill.add_effects
            if len(candidates) == 1 and not plan_one:
                return 0.0, bound.label, end, after
            planned = self.plans(goal, end, after, planner)
            cost = planned.cost if planned.solved and planned.cost is not None else float("inf")
            if best is None or cost < best[0]:
                best = (float(cost), bound.label, end, after)
        assert best is not None  # a skill has at least its recorded binding
        return best
