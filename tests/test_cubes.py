"""N cubes: the scene composed with 1-3 cubes, their world vector and facts, placements
anywhere in the counter square without overlap, and the errors."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import mujoco
import numpy as np
import pytest

from osg_control.cli import main
from osg_control.domain.binding import bind_step
from osg_control.domain.frames import sample_placements
from osg_control.domain.registry import domain_override, get_domain
from osg_control.environment.arm_env import GRIPPER_OPEN_CMD
from osg_control.errors import DomainError, EnvOptionError, PlacementError
from osg_control.execution.executor import load_executor, task_env_config
from osg_control.execution.locate import node_at, skill_on_path
from osg_control.kitchen.cubes import CUBE_CLEARANCE, cube_frame, cube_objects
from osg_control.kitchen.env import KitchenEnv
from osg_control.kitchen.scene import build_kitchen_model, kitchen_robot, kitchen_xml_path
from osg_control.kitchen.skills import CUBE, OBJECTS
from osg_control.kitchen.world import (
    CUBE_HALF_SIZE,
    WORLD_FIELDS,
    CubeState,
    cube_count,
    world_facts,
    world_fields,
    world_state_from_array,
)
from osg_control.perception.spec import perception_spec
from osg_control.planning.api import plan_for_goal


def test_one_cube_model_is_the_files_scene_and_more_cubes_are_added_bodies() -> None:
    robot = kitchen_robot("panda")
    one = build_kitchen_model(robot)
    three = build_kitchen_model(robot, cubes=3)
    assert three.nbody == one.nbody + 2 and three.nq == one.nq + 14
    with pytest.raises(KeyError):
        one.body("cube2")
    scene = mujoco.MjModel.from_xml_path(str(kitchen_xml_path()))
    assert [scene.body(i).name for i in range(scene.nbody)] == [
        one.body(i).name for i in range(scene.nbody)
    ]  # the file's bodies first, in its order
    colours = {tuple(three.geom_rgba[three.geom(n).id]) for n in ("cube", "cube2", "cube3")}
    assert len(colours) == 3
    np.testing.assert_array_equal(three.geom_size[three.geom("cube3").id], [CUBE_HALF_SIZE] * 3)


@pytest.mark.parametrize("cubes", [2, 3])
def test_each_cube_has_its_world_fields_grasp_and_facts(cubes: int) -> None:
    env = KitchenEnv(skill="move-home-to-cube", cubes=cubes)
    env.reset(seed=0)
    world = env.read_world()
    assert world.shape == (len(world_fields(cubes)),) and cube_count(len(world)) == cubes
    assert world_fields(cubes)[: len(WORLD_FIELDS)] == WORLD_FIELDS  # cube 1's layout kept
    state = world_state_from_array(world)
    np.testing.assert_array_equal(state.as_array(), world)
    facts = env.facts()
    expected = {"cube-on-counter", *(f"(on-counter cube-{k})" for k in range(2, cubes + 1))}
    assert expected <= facts and "hand-empty" in facts
    assert env.percept().facts >= expected  # the robot perception reports every cube
    # cube 2 lifted in a gripper: its own facts, not cube 1's, and the hand not empty
    lifted = CubeState((0.5, -0.2, 0.2), (1.0, 0.0, 0.0, 0.0), True)
    held = world_facts(dataclasses.replace(state, more_cubes=(lifted, *state.more_cubes[1:])))
    assert {"(holding cube-2)", "(lifted cube-2)"} <= held
    assert "hand-empty" not in held and "holding-cube" not in held


def test_cube_placements_cover_the_square_without_overlap_and_follow_the_seed() -> None:
    frames = cube_objects(3)
    rng = np.random.default_rng(11)
    draws = [sample_placements(frames, rng) for _ in range(300)]
    for placed in draws:
        xy = np.array([placed[name][:2] for name in ("cube", "cube2", "cube3")])
        assert np.all(xy >= CUBE.region_low) and np.all(xy <= CUBE.region_high)
        gaps = [np.linalg.norm(xy[i] - xy[j]) for i in range(3) for j in range(i + 1, 3)]
        assert min(gaps) >= 2 * CUBE_CLEARANCE
    third = np.array([d["cube3"][:2] for d in draws])
    assert np.ptp(third[:, 0]) > 0.17 and np.ptp(third[:, 1]) > 0.17  # anywhere in it
    again = sample_placements(frames, np.random.default_rng(11))
    assert all(np.array_equal(again[k], draws[0][k]) for k in again)
    # one cube: exactly the draw of the one-cube scene (one uniform draw)
    one = sample_placements(OBJECTS, np.random.default_rng(5))["cube"]
    np.testing.assert_array_equal(
        one[:2], np.random.default_rng(5).uniform((0.4, -0.3), (0.6, -0.1))
    )


def test_more_cubes_than_fit_are_a_named_error() -> None:
    with pytest.raises(PlacementError, match="fits no more"):
        sample_placements([cube_frame(k) for k in range(1, 10)], np.random.default_rng(0))
    with pytest.raises(EnvOptionError, match="1 to 3 cubes"):
        KitchenEnv(cubes=4)


def test_placed_cubes_rest_where_asked_and_overlapping_ones_are_refused() -> None:
    env = KitchenEnv(skill="move-home-to-cube", cubes=2)
    placements = sample_placements(env.objects, np.random.default_rng(3))
    world = env.placement_world(placements, None)
    assert set(world) == {"cube_pos", "cube2_pos", "valve_pos"}  # the valve placed too
    env.reset(seed=1, options={"world": world})
    assert env.world().valve_pos == tuple(placements["valve"][:2])
    cubes = env.world().cubes
    for cube, name in zip(cubes, ("cube", "cube2"), strict=True):
        np.testing.assert_allclose(cube.pos[:2], placements[name][:2], atol=2e-3)
    before = env.data.qpos.copy()
    overlapping = {"cube_pos": [0.5, -0.2, CUBE_HALF_SIZE], "cube2_pos": [0.52, -0.19, 0.0225]}
    with pytest.raises(PlacementError, match="cube_pos .* and cube2_pos"):
        env.reset(seed=2, options={"world": overlapping})
    with pytest.raises(PlacementError, match="overlapping"):  # cube 2 onto cube 1's rest place
        env.reset(seed=2, options={"world": {"cube2_pos": [0.5, -0.2, CUBE_HALF_SIZE]}})
    np.testing.assert_array_equal(env.data.qpos, before)  # refused before anything moved


def test_a_two_cube_task_runs_in_the_kitchen_with_two_cubes() -> None:
    kitchen = get_domain("kitchen")
    task = kitchen.task("two-cubes-in-cabinet")
    scene = kitchen.for_task(task)
    assert scene.ref == "kitchen[cube=2]" and get_domain(scene.ref) is get_domain(scene.ref)
    assert scene.lifting.of_type("cube") == ["cube-1", "cube-2"]
    assert [t.name for t in scene.tasks] == ["two-cubes-in-cabinet", "pick-up-cube-2"]
    assert "(on-counter cube-2)" in scene.start_world and "(holding cube-2)" in scene.facts
    assert [o.name for o in scene.objects] == ["cube", "cube2", "door", "valve"]
    assert kitchen.for_task(kitchen.task("pick-up")) is kitchen
    assert kitchen.with_counts({"cube": 1}) is kitchen
    env = scene.make_env()
    assert env.cubes == 2 and len(env.read_world()) == len(scene.world_fields)
    with pytest.raises(DomainError, match="1 to 3 cubes"):
        kitchen.with_counts({"cube": 4})
    with pytest.raises(DomainError, match="only the number of cubes"):
        kitchen.with_counts({"valve": 2})


def test_facts_per_cube_instance_and_a_plan_for_both_cubes() -> None:
    scene = get_domain("kitchen[cube=2]")
    facts = scene.facts_of(np.array(_two_cube_world()))
    assert {"cube-in-cabinet", "(on-counter cube-2)", "hand-empty"} <= facts
    assert scene.lifting.atom("(in-cabinet cube-2)") == ("in-cabinet", "cube-2")
    result = plan_for_goal(scene, ["(door-open door-1) (in-cabinet cube-1) (in-cabinet cube-2)"])
    assert result.solved
    steps = list(result.actions)
    assert "grab-cube cube-1" in steps and "grab-cube cube-2" in steps
    assert steps.index("release-cube cube-1") < steps.index("grab-cube cube-2")  # one at a time
    bound = bind_step(scene.lifting, scene.skills_by_name, "grab-cube cube-2")
    assert bound.frames == {"cube": "cube2"} and "(holding cube-2)" in bound.skill.add_effects


def test_cli_plans_and_exports_two_cubes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    goal = "(door-open door-1) (in-cabinet cube-2)"
    assert main(["--domain", "kitchen[cube=2]", "plan", "--goal", goal, "--json"]) == 0
    plan = json.loads(capsys.readouterr().out)
    assert "place-cube-in-cabinet cube-2" in [s["action"] for s in plan["steps"]]
    assert main(["plan", "--goal", "(in-cabinet cube-2)"]) == 2  # one cube: no cube-2
    assert "unknown object 'cube-2'" in capsys.readouterr().err
    assert main(["--domain", "kitchen[cube=9]", "plan", "--goal", "door-open"]) == 2
    assert "1 to 3 cubes" in capsys.readouterr().err
    camera = ["--domain", "kitchen[cube=2]", "run", "--goal", "(lifted cube-2)"]
    assert main([*camera, "--perception", "camera", "--json"]) == 0  # each cube its colour
    assert json.loads(capsys.readouterr().out)["success_rate"] == 1.0
    assert main(["pddl", "export", "--out", str(tmp_path)]) == 0
    problem = (tmp_path / "problems" / "two-cubes-in-cabinet.pddl").read_text()
    assert "(:objects cube-1 cube-2 - cube" in problem and "(on-counter cube-2)" in problem


def _two_cube_world() -> list[float]:
    """Door shut, cube 1 in the cabinet, cube 2 on the counter, nothing held."""
    cube_1 = [0.64, 0.30, 0.1225, 1.0, 0.0, 0.0, 0.0, 0.0]
    cube_2 = [0.45, -0.15, CUBE_HALF_SIZE, 1.0, 0.0, 0.0, 0.0, 0.0]
    return [0.0, 0.0, *cube_1[:7], 0.0, 0.0, *cube_2]


def test_the_entry_skill_is_bound_to_the_goals_cube() -> None:
    scene = get_domain("kitchen[cube=2]")
    executor = load_executor(scene, max_replans=0)
    facts = set(scene.start_world)
    for cube in ("cube-1", "cube-2"):
        label, end, after = executor.entry.bind("move-home-to-cube", [f"(lifted {cube})"], facts)
        place = "above-cube" if cube == "cube-1" else f"above-cube {cube}"  # recorded: bare
        assert (label, end) == (f"move-home-to-cube {cube}", place)
        plan = executor._plans([f"(lifted {cube})"], end, after, "astar")
        assert list(plan.actions) == [f"grab-cube {cube}", f"pick-up-cube {cube}"]


def test_an_executed_two_cube_episode_puts_both_cubes_in_the_cabinet() -> None:
    scene = get_domain("kitchen[cube=2]")
    task = scene.task("two-cubes-in-cabinet")
    env = scene.make_env(config=task_env_config(perception_spec("robot", 0.0)))
    world = env.placement_world(sample_placements(scene, np.random.default_rng(7)), None)
    obs, _ = env.reset(seed=7, options={"facts": task.world, "world": world})
    result = load_executor(scene, max_replans=2).execute(task.goal, env, obs)
    assert result.success and set(task.goal) <= env.facts(), result.to_dict()
    assert all(cube.in_cabinet for cube in env.world().cubes)
    bound = [o.skill for o in result.outcomes]
    assert bound.count("grab-cube") >= 2  # each cube grabbed in its own frame


def test_a_goal_on_cube_2_enters_toward_it_from_off_the_graph() -> None:
    """Goal-aware entry weighs each binding of a candidate: from the cabinet with the door
    shut, toward cube 2 (before, each candidate was costed from cube 1's place, which made
    the way via the valve look cheaper)."""
    scene = get_domain("kitchen[cube=2]")
    executor = load_executor(scene, max_replans=0)
    obs = np.zeros(10)
    obs[:3], obs[3:7], obs[7] = (0.395, 0.317, 0.327), (0.0, 1.0, 0.0, 0.0), GRIPPER_OPEN_CMD
    facts = set(scene.start_world)
    offsets = {"cube": np.zeros(3), "cube2": np.array([0.04, -0.06, 0.0])}
    entry, plan, _ = executor.plan(["(lifted cube-2)"], obs, facts, offsets)
    assert entry is not None and entry.endswith("-to-cube cube-2")  # to above cube 2
    assert plan == ["grab-cube cube-2", "pick-up-cube cube-2"]


def test_the_robot_is_located_on_each_cubes_nodes_and_paths() -> None:
    scene = get_domain("kitchen[cube=2]")
    offsets = {"cube": np.zeros(3), "cube2": np.array([-0.09, 0.09, 0.0])}
    obs = np.zeros(10)
    obs[3:7], obs[7] = (0.0, 1.0, 0.0, 0.0), GRIPPER_OPEN_CMD
    facts = set(scene.start_world)
    obs[:3] = np.add(scene.nodes["above-cube"].position, offsets["cube2"])
    assert node_at(scene, obs, facts, offsets) == "above-cube cube-2"
    obs[:3] = scene.nodes["above-cube"].position
    assert node_at(scene, obs, facts, offsets) == "above-cube"
    grasp = np.add(scene.nodes["cube-grasped"].position, offsets["cube2"])
    obs[:3] = (obs[:3] + offsets["cube2"] + grasp) / 2  # half-way down to cube 2
    skills = scene.skills_by_name.values()
    assert skill_on_path(scene, obs, facts, skills, offsets) == "grab-cube cube-2"
    plan = plan_for_goal(scene, "(lifted cube-2)", "above-cube cube-2", sorted(facts))
    assert plan.actions == ("grab-cube cube-2", "pick-up-cube cube-2")


def test_two_cubes_with_another_robot_keep_both_choices() -> None:
    domain = get_domain("kitchen[cube=2]@ur5")
    assert (domain.ref, domain.robot) == ("kitchen[cube=2]@ur5", "ur5")
    assert domain.lifting.of_type("cube") == ["cube-1", "cube-2"]
    ur5 = get_domain("kitchen@ur5")
    two = ur5.for_task(ur5.task("two-cubes-in-cabinet"))
    assert (two.ref, two.robot) == ("kitchen[cube=2]@ur5", "ur5")
    with domain_override(domain, "kitchen[cube=2]"):  # what osg --robot ur5 does
        assert get_domain("kitchen[cube=2]") is domain
    assert get_domain("kitchen[cube=2]").robot == "panda"
