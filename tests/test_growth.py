"""Growing a domain's graph by data: adding skills leaves every other skill's data and weights
as they were, and measured success rates choose the likelier of two plans."""

from __future__ import annotations

import dataclasses
import hashlib
import math
from pathlib import Path

import numpy as np
import pytest
from safetensors.numpy import load_file

from osg_control.cli import main
from osg_control.data.collect import collect_skill
from osg_control.domain.base import Domain
from osg_control.domain.registry import get_domain, register_domain
from osg_control.planning.api import plan_for_goal
from osg_control.planning.graph import graph_from_specs
from osg_control.planning.pddl_io import skill_cost

KITCHEN = get_domain("kitchen")
VALVE_SKILLS = {s.name for s in KITCHEN.skills if "valve" in s.name}
SKILL = "grab-cube"


def _before_valve() -> Domain:
    """The kitchen as it was before the valve's skills were added (same name order)."""
    return dataclasses.replace(
        KITCHEN,
        name="kitchen-before-valve",
        skills=tuple(s for s in KITCHEN.skills if s.name not in VALVE_SKILLS),
        tasks=tuple(t for t in KITCHEN.tasks if "valve" not in t.name),
        training={k: v for k, v in KITCHEN.training.items() if k not in VALVE_SKILLS},
    )


def _array_hashes(path: Path) -> dict[str, str]:
    import h5py

    with h5py.File(path, "r") as f:
        return {key: hashlib.sha256(f[key][()].tobytes()).hexdigest() for key in f}


@pytest.mark.slow
def test_adding_skills_changes_no_other_skills_data_or_weights(tmp_path: Path) -> None:
    assert len(VALVE_SKILLS) == 5
    register_domain("kitchen-before-valve", _before_valve)
    before, after = get_domain("kitchen-before-valve"), KITCHEN
    assert len(after.skills) == len(before.skills) + len(VALVE_SKILLS)
    for domain in (before, after):
        out = tmp_path / domain.name
        collect_skill(domain, SKILL, 6, 0, out / "data", None, False, chunk_episodes=3)
        argv = ["--domain", domain.name, "train", "--skill", SKILL, "--steps", "20"]
        argv += ["--data", str(out / "data"), "--out", str(out / "skills"), "--threads", "1"]
        assert main(argv) == 0
    data = [_array_hashes(tmp_path / d.name / "data" / f"{SKILL}.h5") for d in (before, after)]
    assert data[0] == data[1]  # every recorded array byte for byte
    weights = [
        load_file(str(tmp_path / d.name / "skills" / f"{SKILL}.safetensors"))
        for d in (before, after)
    ]
    assert weights[0].keys() == weights[1].keys()
    for key in weights[0]:
        assert np.array_equal(weights[0][key], weights[1][key]), key


def test_measured_rates_choose_the_likelier_of_two_plans() -> None:
    # cabinet-front -> above-cube: one skill, or two through home.
    goal, node = "(at above-cube)", "cabinet-front"
    world = ("door-open", "cube-on-counter", "hand-empty", "valve-closed")
    uniform = plan_for_goal(KITCHEN, goal, node, world)
    assert uniform.actions == ("move-cabinet-to-cube cube-1",)  # above cube-1
    rates = {"move-cabinet-to-cube": 0.6, "move-cabinet-to-home": 0.95, "move-home-to-cube": 0.95}
    measured = plan_for_goal(
        KITCHEN, goal, node, world, graph=graph_from_specs(KITCHEN, success_rates=rates)
    )
    assert measured.actions == ("move-cabinet-to-home", "move-home-to-cube cube-1")
    assert 0.95 * 0.95 > 0.6  # the two-skill path is the likelier one ...
    assert measured.cost == 2 * skill_cost(0.95) == 2 * round(-math.log(0.95) * 1000)


@pytest.mark.parametrize("planner", ["astar", "ucs", "auto"])
def test_costs_are_the_same_in_every_planner(planner: str) -> None:
    rates = {s.name: 0.9 for s in KITCHEN.skills}
    graph = graph_from_specs(KITCHEN, success_rates=rates)
    result = plan_for_goal(KITCHEN, "valve-open", planner=planner, graph=graph)
    assert result.actions == (
        "move-home-to-valve valve-1", "lower-to-valve valve-1", "push-valve-open valve-1"
    )  # fmt: skip
    assert result.cost == 3 * skill_cost(0.9)
