"""The valve's place as a ``world`` reset option: checked, clear of the cube's square, the
file's place by default, and a real MuJoCo push that turns the valve where it was moved;
its place as world fields (old vectors still read), read by a sensor whose noise leaves
every other draw as it was, and its nodes following it (``VALVE``)."""

from __future__ import annotations

import numpy as np
import pytest

from osg_control.data.scripted import ScriptedPolicy
from osg_control.domain.frames import offsets_of, sample_placements, shifted_nodes, shifted_skill
from osg_control.environment.arm_env import EnvConfig
from osg_control.errors import EnvOptionError
from osg_control.kitchen.cubes import cube_sensors
from osg_control.kitchen.detectors import WORLD_SENSORS
from osg_control.kitchen.env import KitchenEnv
from osg_control.kitchen.options import COUNTER_OBSTACLES, WORLD_OPTIONS
from osg_control.kitchen.skills import CUBE, NODES, SKILLS_BY_NAME
from osg_control.kitchen.valve import (
    VALVE,
    VALVE_BODY_Z,
    VALVE_HINGE,
    VALVE_NODES,
    VALVE_SENSORS,
    VALVE_SHIFT,
    valve_footprint,
    valve_position,
)
from osg_control.kitchen.world import (
    CUBE_HALF_SIZE,
    VALVE_FIELDS,
    VALVE_OPEN_MIN,
    cube_count,
    world_fields,
    world_state_from_array,
)
from osg_control.perception.sensors import noisy_world, sensor_slices
from osg_control.perception.spec import perception_spec

ABOVE = NODES["above-valve"].position
"""A start clear of the valve wherever it is (the push's own start lies in a moved knob)."""


@pytest.fixture(scope="module")
def env() -> KitchenEnv:
    return KitchenEnv(skill="push-valve-open")


def _valve_xyz(env: KitchenEnv) -> np.ndarray:
    return env.data.xpos[env.scene.valve_body].copy()


def test_default_is_the_files_place(env: KitchenEnv) -> None:
    assert "valve_pos" in WORLD_OPTIONS
    file_place = np.array([*VALVE_HINGE, VALVE_BODY_Z])
    assert env.model.body_pos[env.scene.valve_body].tobytes() == file_place.tobytes()
    assert valve_position({}).tobytes() == file_place.tobytes()
    env.reset(seed=0)
    np.testing.assert_array_equal(_valve_xyz(env), file_place)


def test_valve_pos_moves_the_body_for_one_episode(env: KitchenEnv) -> None:
    moved = (VALVE_HINGE[0] + 0.03, VALVE_HINGE[1] - 0.04)
    env.reset(seed=1, options={"world": {"valve_pos": list(moved)}, "position": ABOVE})
    np.testing.assert_allclose(_valve_xyz(env), [*moved, VALVE_BODY_Z], atol=1e-12)
    lever = env.data.geom_xpos[env.model.geom("valve_lever").id]
    np.testing.assert_allclose(lever[:2], [moved[0] + 0.04, moved[1]], atol=2e-3)
    env.reset(seed=1)  # back at the file's place
    np.testing.assert_array_equal(_valve_xyz(env), [*VALVE_HINGE, VALVE_BODY_Z])


@pytest.mark.parametrize(
    ("value", "words"),
    [
        ([VALVE_HINGE[0] + VALVE_SHIFT + 0.001, VALVE_HINGE[1]], "outside the valve's region"),
        ([VALVE_HINGE[0], VALVE_HINGE[1] + 0.05], "outside the valve's region"),
        ([float("nan"), VALVE_HINGE[1]], "finite numbers of shape (2,)"),
        ([0.35, -0.45, 0.03], "finite numbers of shape (2,)"),
        ("here", "finite numbers of shape (2,)"),
    ],
)
def test_bad_valve_pos_is_refused_and_changes_nothing(
    env: KitchenEnv, value: object, words: str
) -> None:
    env.reset(seed=2)
    before = _valve_xyz(env)
    with pytest.raises(EnvOptionError, match="world.valve_pos") as err:
        env.reset(seed=2, options={"world": {"valve_pos": value}})
    assert words in str(err.value)
    np.testing.assert_array_equal(env.model.body_pos[env.scene.valve_body], before)


def test_valve_region_clears_the_cube_square_and_the_cabinet() -> None:
    """Every corner of the valve's region keeps its footprint off the cube's square (the
    cube's edge included) and the cabinet's plinth."""
    assert CUBE.region_low is not None and CUBE.region_high is not None
    square_low = np.asarray(CUBE.region_low) - CUBE_HALF_SIZE
    square_high = np.asarray(CUBE.region_high) + CUBE_HALF_SIZE
    boxes = [(square_low, square_high), *map(np.asarray, COUNTER_OBSTACLES.values())]
    for dx in (-VALVE_SHIFT, VALVE_SHIFT):
        for dy in (-VALVE_SHIFT, VALVE_SHIFT):
            low, high = map(
                np.asarray,
                valve_footprint({"valve_pos": [VALVE_HINGE[0] + dx, VALVE_HINGE[1] + dy]}),
            )
            for other_low, other_high in boxes:
                overlap = np.all(low < np.asarray(other_high)) and np.all(
                    np.asarray(other_low) < high
                )
                assert not overlap, (dx, dy, other_low, other_high)


def test_cube_check_follows_the_moved_valve(env: KitchenEnv) -> None:
    cube = [0.40, -0.36, CUBE_HALF_SIZE]  # clear of the valve at its file place
    env.reset(seed=3, options={"world": {"cube_pos": cube}, "position": ABOVE})
    moved = [VALVE_HINGE[0] + 0.04, VALVE_HINGE[1] + 0.04]
    with pytest.raises(EnvOptionError, match="cuts into the valve"):
        env.reset(
            seed=3, options={"world": {"cube_pos": cube, "valve_pos": moved}, "position": ABOVE}
        )


def _push(env: KitchenEnv, offset: np.ndarray, script_offset: np.ndarray) -> float:
    """The valve's angle after the scripted push, its waypoints moved by ``script_offset``,
    with the valve (and the push's start) moved by ``offset``."""
    skill = SKILLS_BY_NAME["push-valve-open"]
    start = np.asarray(NODES[skill.start].position) + offset
    world = {"valve_pos": [VALVE_HINGE[0] + offset[0], VALVE_HINGE[1] + offset[1]]}
    obs, _ = env.reset(seed=4, options={"world": world, "position": start, "radius": 0.0})
    policy = ScriptedPolicy(
        shifted_skill(skill, script_offset), np.random.default_rng(4), bounds=env.action_bounds
    )
    policy.reset()
    for _ in range(120):
        obs, *_ = env.step(policy(obs))
        if policy.done:
            break
    return env.world().valve_angle


@pytest.mark.parametrize("offset", [(-0.04, -0.04), (-0.04, 0.04), (0.03, -0.03)])
def test_scripted_push_turns_the_moved_valve(env: KitchenEnv, offset: tuple) -> None:
    """The push's waypoints moved with the valve (``frames.shifted_skill``) turn it open
    where the option put it: the skill's geometry carries to another place."""
    shift = np.array([*offset, 0.0])
    assert abs(_push(env, shift, shift)) >= VALVE_OPEN_MIN


def test_push_at_the_files_place_misses_a_moved_valve(env: KitchenEnv) -> None:
    """The same push aimed at the file's place leaves a valve moved 4 cm each way shut:
    the nodes must follow the valve."""
    assert abs(_push(env, np.array([-0.04, -0.04, 0.0]), np.zeros(3))) < VALVE_OPEN_MIN


def test_an_executed_turn_valve_with_the_valve_moved() -> None:
    """The learned executor (shipped defaults, ``robot`` perception) runs ``turn-valve``
    with the valve moved by up to 4 cm along each axis (a fixed seed; this draw moves it
    more than 2 cm): its nodes follow the valve's perceived place, so the skills, learned
    at the file's place, act in its frame and turn it."""
    from osg_control.domain.registry import get_domain
    from osg_control.execution.executor import load_executor, task_env_config
    from osg_control.kitchen.disturbances import moved_valve_episode
    from osg_control.perception.spec import perception_spec

    kitchen = get_domain("kitchen")
    executor = load_executor(kitchen, None, max_replans=2)
    moved = KitchenEnv(config=task_env_config(perception_spec("robot")))
    episode = moved_valve_episode(executor, moved, np.random.default_rng([11, 0]), shift=0.04)
    assert 0.02 < max(map(abs, episode.shift)) <= 0.04
    np.testing.assert_allclose(
        _valve_xyz(moved)[:2], np.add(VALVE_HINGE, episode.shift), atol=1e-12
    )
    assert episode.opened


def test_world_vector_ends_with_the_valves_place_and_old_widths_read() -> None:
    """The valve's fields come last whatever the cubes; a vector stored before them (11 +
    8 per further cube) reads with the valve at the file's place; other widths are refused."""
    moved = (VALVE_HINGE[0] + 0.03, VALVE_HINGE[1] - 0.02)
    for cubes in (1, 2, 3):
        fields = world_fields(cubes)
        assert fields[-2:] == VALVE_FIELDS and len(fields) == 11 + 8 * (cubes - 1) + 2
        world = np.zeros(len(fields))
        world[-2:] = moved
        assert cube_count(len(fields)) == cubes == cube_count(len(fields) - 2)
        assert world_state_from_array(world).valve_pos == moved
        old = world_state_from_array(world[:-2])
        assert old.valve_pos == VALVE_HINGE and len(old.more_cubes) == cubes - 1
        np.testing.assert_array_equal(old.as_array()[:-2], world[:-2])
    for width in (12, 14, 20, 35):
        with pytest.raises(ValueError, match="valve"):
            cube_count(width)


def test_fixture_noise_leaves_every_other_draw_unchanged() -> None:
    """The valve's sensor draws from its own stream: the other fields' readings are bit for
    bit those of a vector without the valve's fields from the same generator."""
    spec = perception_spec("robot")
    world = np.linspace(0.1, 1.3, len(world_fields(2)))
    new = noisy_world(
        spec,
        np.random.default_rng(5),
        world,
        sensor_slices({**WORLD_SENSORS, **cube_sensors(2), **VALVE_SENSORS}),
        np.random.default_rng(99),
    )
    old = noisy_world(
        spec,
        np.random.default_rng(5),
        world[:-2],
        sensor_slices({**WORLD_SENSORS, **cube_sensors(2)}),
    )
    np.testing.assert_array_equal(new[:-2], old)
    assert 0 < np.max(np.abs(new[-2:] - world[-2:])) < 5 * spec.object_noise


@pytest.mark.parametrize("perception", ["paper", "robot"])
def test_the_valve_is_perceived_where_it_was_moved(perception: str) -> None:
    """Exact under ``paper``, 1 cm noise under ``robot``; the executor's offsets (read from
    the percept) move the three valve nodes with it."""
    from osg_control.domain.registry import get_domain

    kitchen = get_domain("kitchen")
    env = KitchenEnv(config=EnvConfig(perception=perception_spec(perception)))
    shift = np.array([-0.03, 0.04])
    env.reset(seed=2, options={"world": {"valve_pos": (np.add(VALVE_HINGE, shift)).tolist()}})
    seen = offsets_of(kitchen.objects, kitchen.world_fields, env.percept().world)["valve"]
    tolerance = 1e-12 if perception == "paper" else 0.05
    np.testing.assert_allclose(seen[:2], shift, atol=tolerance)
    nodes = shifted_nodes(kitchen, {"valve": seen})
    for node in VALVE_NODES:
        assert node.anchor == VALVE.name
        np.testing.assert_allclose(
            np.subtract(nodes[node.name].position, node.position), seen, atol=1e-4
        )
    env.close()


def test_valve_placed_after_the_cubes_from_its_own_stream() -> None:
    """``--randomize-objects`` places the valve in its region without changing the cubes'
    draws or the caller's later draws; Algorithm 1 leaves it (and the valve skills' data)
    where the file has it."""
    from osg_control.data.collect import touches_objects
    from osg_control.domain.registry import get_domain

    kitchen = get_domain("kitchen[cube=2]")
    rng, before = np.random.default_rng(7), np.random.default_rng(7)
    placed = sample_placements(kitchen, rng)
    cubes_only = sample_placements([f for f in kitchen.objects if f.name != "valve"], before)
    assert list(placed)[-1] == "valve" and list(placed)[:-1] == list(cubes_only)
    for name, pos in cubes_only.items():
        np.testing.assert_array_equal(placed[name], pos)
    assert rng.integers(2**31) == before.integers(2**31)
    assert np.all(np.abs(placed["valve"][:2] - VALVE_HINGE) <= VALVE_SHIFT)
    assert placed["valve"][2] == VALVE.rest_z
    assert "valve" not in sample_placements(kitchen, np.random.default_rng(7), collecting=True)
    env = KitchenEnv(cubes=2)
    assert env.placement_world(placed, None)["valve_pos"] == placed["valve"][:2].tolist()
    for name in ("lower-to-valve", "push-valve-open", "move-valve-to-home"):
        assert not touches_objects(kitchen, kitchen.skills_by_name[name])
    env.close()
