"""``Domain.step_cost``: a skill's step budget enters its plan cost, so of two equally
likely plans the shorter one is chosen (the FrankaKitchen env's 280-step limit)."""

from __future__ import annotations

import dataclasses

from osg_control.domain.registry import get_domain
from osg_control.planning.api import plan_for_goal
from osg_control.planning.graph import graph_from_dict, graph_from_specs, step_budget
from osg_control.planning.pddl_io import skill_cost

GOAL = "microwave-open kettle-moved light-on slide-open"


def test_edges_carry_the_budget_cost_and_round_trip() -> None:
    domain = get_domain("franka-kitchen")
    graph = graph_from_specs(domain)
    for spec in domain.skills:
        assert graph.edge(spec.name).step_cost == round(domain.step_cost * step_budget(spec))
    assert graph.edge("move-slide-to-home").step_cost == 2 * 65
    assert graph_from_dict(graph.to_dict()).edges == graph.edges
    assert get_domain("kitchen").step_cost == 0.0  # the kitchen's costs are unchanged


def test_the_shorter_of_two_equal_plans_wins() -> None:
    domain = get_domain("franka-kitchen")
    rates = {spec.name: 0.99 for spec in domain.skills}
    timed = plan_for_goal(domain, GOAL, graph=graph_from_specs(domain, success_rates=rates))
    assert timed.solved
    # Ending at the slide cabinet (no 65-step return from it) and the direct moves.
    assert timed.actions[-1] == "push-slide"
    assert "move-slide-to-home" not in timed.actions
    assert "move-light-to-slide" in timed.actions
    budgets = {s.name: step_budget(s) for s in domain.skills}
    untimed_domain = dataclasses.replace(domain, step_cost=0.0)
    untimed = plan_for_goal(
        untimed_domain, GOAL, graph=graph_from_specs(untimed_domain, success_rates=rates)
    )
    assert len(untimed.actions) == len(timed.actions)  # as likely: the same count of skills
    assert sum(budgets[a] for a in timed.actions) <= sum(budgets[a] for a in untimed.actions)
    assert timed.cost == sum(skill_cost(0.99) + 2 * budgets[a] for a in timed.actions)
