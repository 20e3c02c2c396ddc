"""Skill specifications: JSON round trip, validation errors, Algorithm 1's step budgets."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from osg_control.data.scripted import ScriptedPolicy
from osg_control.domain.spec import SkillSpec, skill_from_json
from osg_control.errors import SkillSpecError
from osg_control.kitchen.domain import kitchen_domain
from osg_control.kitchen.skills import (
    RELEASE_STEPS,
    SKILLS,
    Waypoint,
    get_skill,
    validate_skill,
)
from osg_control.kitchen.world import WorldState, world_facts


@pytest.mark.parametrize("skill", SKILLS, ids=lambda s: s.name)
def test_every_spec_round_trips_through_json(skill: SkillSpec) -> None:
    # parameters are the planner's view, not part of what the data record (spec.to_json)
    assert skill_from_json(skill.to_json()) == dataclasses.replace(skill, parameters=())
    assert "parameters" not in json.loads(skill.to_json())


def test_a_waypoint_out_of_reach_is_named_with_its_skill() -> None:
    """Reach is the robot's (``domain.reach``, checked by ``with_robot``): a waypoint 1.5 m
    out is named, with its skill and index, for the kitchen's own Panda too."""
    from osg_control.domain.reach import unreachable
    from osg_control.robots.registry import get_robot

    kitchen = kitchen_domain()
    far = dataclasses.replace(
        get_skill("grab-cube"), waypoints=(Waypoint((1.5, 0.0, 0.2), "open"),)
    )
    skills = tuple(far if s.name == far.name else s for s in kitchen.skills)
    missed = unreachable(dataclasses.replace(kitchen, skills=skills), get_robot("panda"))
    assert len(missed) == 1 and missed[0].startswith("skill 'grab-cube' waypoint 0"), missed


def test_missing_field_names_the_skill() -> None:
    data = json.loads(get_skill("pick-up-cube").to_json())
    del data["waypoints"]
    with pytest.raises(SkillSpecError, match="'pick-up-cube'.*missing or malformed"):
        skill_from_json(data)


def test_waypoint_budget_below_one_is_refused() -> None:
    skill = get_skill("release-cube")
    bad = dataclasses.replace(skill, waypoints=(Waypoint((0.5, 0.0, 0.3), "open", 0),))
    with pytest.raises(SkillSpecError, match=r"'waypoints\[0\].steps'"):
        validate_skill(bad)


def test_release_waypoint_has_its_own_budget() -> None:
    skill = get_skill("release-cube")
    policy = ScriptedPolicy(skill, np.random.default_rng(0), bounds=kitchen_domain().action_bounds)
    policy.reset()
    rest = skill.script.steps_per_waypoint
    assert skill.waypoints[0].steps == RELEASE_STEPS
    obs = np.zeros(10)
    obs[:3] = skill.waypoints[0].position
    obs[3:7] = (0.0, 1.0, 0.0, 0.0)
    obs[7] = -1.0  # gripper closed: the first waypoint releases it
    targets = []
    while not policy.done:
        action = policy(obs)
        targets.append(action[6])
        obs[7] = 1.0 if action[6] > 0.5 else obs[7]
    assert len(targets) == RELEASE_STEPS + rest
    assert targets[0] == 1.0 and not any(targets[1:])


def test_a_held_cube_inside_the_cabinet_is_not_yet_placed() -> None:
    held = WorldState(0.4, 0.0, (0.64, 0.30, 0.135), (1.0, 0.0, 0.0, 0.0), True, False)
    released = dataclasses.replace(held, cube_grasped=False)
    assert "cube-in-cabinet" not in world_facts(held)
    assert {"cube-in-cabinet", "hand-empty"} <= world_facts(released)


def test_every_initiation_region_covers_the_termination_regions_ending_there() -> None:
    # A skill may start wherever a skill ending at its start node stopped (within that
    # skill's success tolerance), so its data must cover at least that far.
    for before in SKILLS:
        for after in SKILLS:
            if after.start == before.end:
                assert after.start_radius >= before.success_tolerance, (before.name, after.name)
