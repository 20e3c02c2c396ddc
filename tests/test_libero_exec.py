"""Plans executed in LIBERO's envs from percepts (the ``libero`` extra; skipped without
it): the fixture sensor, the facts read from percepts, an operator's controller, and the
``scripted-plan`` policy end to end, scored by the env's ``check_success()``."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from osg_control import cli  # noqa: E402
from osg_control.libero.benchmark import Job, run_job  # noqa: E402
from osg_control.libero.clearance import (  # noqa: E402
    TRANSIT_CLEARANCE,
    hand_clearance,
    transit_height,
)
from osg_control.libero.controllers import operator_legs  # noqa: E402
from osg_control.libero.drive import JointTargetDriver  # noqa: E402
from osg_control.libero.env import LiberoEnv  # noqa: E402
from osg_control.libero.executor import PlanExecutor  # noqa: E402
from osg_control.libero.facts import holds, perceived_init  # noqa: E402
from osg_control.libero.grasp import (  # noqa: E402
    GRASP_CLEARANCE,
    RETRY_SHIFT,
    Grip,
    chosen_grip,
    grasp_point,
    grip,
)
from osg_control.libero.legs import Context, LegRunner  # noqa: E402
from osg_control.libero.perception import FIXTURE_NOISE, LiberoPerception  # noqa: E402
from osg_control.libero.pick_place import holding_ok  # noqa: E402
from osg_control.libero.problem import Atom  # noqa: E402
from osg_control.libero.robot import mounted_panda  # noqa: E402

DRAWER_JOINT = "white_cabinet_1_bottom_level"


@pytest.fixture(scope="module")
def drawer_env():
    """LIBERO-10 task 3: the bowl into the open bottom drawer, then close it."""
    env = LiberoEnv("libero_10", 3)
    yield env
    env.close()


def test_fixture_sensor_is_labelled_noisy_and_seeded(drawer_env: LiberoEnv) -> None:
    """Each reading names its joint and unit; its noise has the stated deviation around the
    simulator's value; the same seed draws the same noise, another seed other noise."""
    obs = drawer_env.reset(0)
    perception = LiberoPerception(drawer_env, seed=3)
    scene, percept = perception.reset(obs, 0)
    reading = percept.fixtures[DRAWER_JOINT]
    assert reading.label == f"fixture-joint/{DRAWER_JOINT}" and reading.unit == "m"
    assert reading.sigma == FIXTURE_NOISE["slide"] == 0.005
    truth = scene.joints[DRAWER_JOINT].q0  # read once as the scene's description
    values = np.array([perception.percept(obs).joint(DRAWER_JOINT) for _ in range(400)])
    assert abs(values.mean() - truth) < 4 * 0.005 / np.sqrt(400)
    assert 0.0045 < values.std() < 0.0055
    again = LiberoPerception(drawer_env, seed=3)
    other = LiberoPerception(drawer_env, seed=4)
    first = again.reset(obs, 0)[1].joint(DRAWER_JOINT)
    assert first == reading.value != other.reset(obs, 0)[1].joint(DRAWER_JOINT)


def test_fixture_placement_is_seeded(drawer_env: LiberoEnv) -> None:
    """LIBERO's reset places the fixtures from NumPy's global generator; the env seeds it
    per episode: the same seed puts the cabinet at the same place whatever was drawn
    before, another seed elsewhere."""
    model = drawer_env.sim.model._model
    cabinet = model.body("white_cabinet_1_main").id

    def cabinet_at(seed: int) -> np.ndarray:
        np.random.seed(12345 + seed)  # what ran before the reset must not matter
        drawer_env.reset(0, seed)
        return model.body_pos[cabinet].copy()

    first = cabinet_at(0)
    assert np.array_equal(first, cabinet_at(0))
    assert not np.array_equal(first, cabinet_at(1))


def test_an_episode_is_the_same_in_any_job() -> None:
    """Initial state 1 of LIBERO-10 task 3 run after state 0 in one env, and alone in a
    fresh one, with the same seed: the same actions (their digest), trace and outcome. (The
    gripper's command state used to carry over from the previous episode, and the fixtures'
    placement came from whatever NumPy's global generator had drawn before.)"""
    after = run_job(Job("libero_10", 3, (0, 1), PlanExecutor, max_steps=150, seed=0))[1]
    alone = run_job(Job("libero_10", 3, (1,), PlanExecutor, max_steps=150, seed=0))[0]
    assert after.init_state == alone.init_state == 1
    assert len(after.trace) > 2  # the pick ran: the comparison covers contacts
    assert (after.actions_sha256, after.trace, after.steps, after.success) == (
        alone.actions_sha256, alone.trace, alone.steps, alone.success)  # fmt: skip


def test_facts_are_read_from_the_percept(drawer_env: LiberoEnv) -> None:
    """The drawer starts open (LIBERO's -0.14 m threshold on the sensed slide), the bowl is
    not in it; the state to plan from says so."""
    obs = drawer_env.reset(0)
    scene, percept = LiberoPerception(drawer_env).reset(obs, 0)
    region = "white_cabinet_1_bottom_region"
    assert holds(scene, percept, Atom("open", (region,)))
    assert not holds(scene, percept, Atom("close", (region,)))
    assert not holds(scene, percept, Atom("in", ("akita_black_bowl_1", region)))
    init = perceived_init(drawer_env.problem, scene, percept)
    assert Atom("open", (region,)) in init
    assert not any(a.predicate == "in" and a.args[0] == "akita_black_bowl_1" for a in init)


def test_pick_controller_lifts_the_object() -> None:
    """``approach`` then ``pick`` of the alphabet soup (LIBERO-Object task 0), deciding from
    percepts: the percept says it is held and lifted, and so does the simulator."""
    env = LiberoEnv("libero_object", 0)
    try:
        obs = env.reset(0)
        perception = LiberoPerception(env)
        scene, percept = perception.reset(obs, 0)
        robot = mounted_panda(env.sim)
        driver = JointTargetDriver(robot)
        ctx = Context(scene, driver, driver.tcp_pose(percept.joints)[1], float(percept.tcp[2]),
                      dict(env.problem.objects), np.r_[robot.mount[0][:2], 0.0])  # fmt: skip
        start_z = float(obs["alphabet_soup_1_pos"][2])
        for operator in ("approach", "pick"):
            runner = LegRunner(operator_legs(ctx, operator, ("alphabet_soup_1",), None), ctx)
            while (action := runner.act(percept)) is not None:
                assert env.steps < 200
                obs = env.step(action)
                percept = perception.percept(obs)
        assert holding_ok(ctx, percept, "alphabet_soup_1", start_z)
        assert obs["alphabet_soup_1_pos"][2] > start_z + 0.05  # the simulator agrees
    finally:
        env.close()


def test_scripted_plan_puts_the_soup_in_the_basket(capsys) -> None:
    """The plan executor on LIBERO-Object task 0, initial states 0-1: planned from the
    percept, run operator by operator within 280 steps, scored by check_success()."""
    argv = ["--domain", "libero", "evaluate", "benchmark", "--suite", "libero_object", "--task",
            "0", "--init-states", "0:2", "--policy", "scripted-plan", "--seed", "1",
            "--json"]  # fmt: skip
    assert cli.main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["policy"] == "scripted-plan" and summary["max_steps"] == 280
    assert summary["seed"] == 1 and summary["fixture_noise"] == FIXTURE_NOISE
    for episode in summary["episode_log"]:
        assert episode["success"] and episode["steps"] < 280
        assert any("pick-out alphabet_soup_1" in line and line.endswith("ok")
                   for line in episode["trace"])  # fmt: skip


@pytest.mark.slow
def test_scripted_plan_closes_the_drawer_on_the_bowl(capsys) -> None:
    """LIBERO-10 task 3, initial state 0: the bowl into the open drawer, then the drawer
    pushed shut (its joint sensed with noise), within 520 steps."""
    argv = ["--domain", "libero", "evaluate", "benchmark", "--suite", "libero_10", "--task",
            "3", "--init-states", "0:1", "--policy", "scripted-plan", "--json"]  # fmt: skip
    assert cli.main(argv) == 0
    (episode,) = json.loads(capsys.readouterr().out)["episode_log"]
    assert episode["success"], episode["trace"]
    assert any(line.endswith("place-in akita_black_bowl_1 white_cabinet_1_bottom_region: ok")
               for line in episode["trace"])  # fmt: skip


def _living_room(task: int, state: int):
    """A LIBERO-10 living-room scene at an initial state: its env, scene, first percept
    and a controllers' context."""
    env = LiberoEnv("libero_10", task)
    obs = env.reset(state)
    scene, percept = LiberoPerception(env).reset(obs, state)
    robot = mounted_panda(env.sim)
    driver = JointTargetDriver(robot)
    ctx = Context(scene, driver, driver.tcp_pose(percept.joints)[1], float(percept.tcp[2]),
                  dict(env.problem.objects), np.r_[robot.mount[0][:2], 0.0])  # fmt: skip
    return env, scene, percept, ctx


def test_grasp_keeps_the_hand_clear_of_a_neighbour() -> None:
    """LIBERO-10 task 1, state 0: the cream cheese box's preferred grasp (across its
    middle) puts the palm on the milk carton beside it (its descent stopped on the carton);
    the grasp taken is a slice of the box the open hand clears it at. A failed pick moves
    the retry to another grasp."""
    env, scene, percept, ctx = _living_room(1, 0)
    try:
        obj = "cream_cheese_1"
        pos, rot = percept.objects[obj]

        def gap(g: Grip) -> float:
            along = rot[:, g.axis] if g.axis is not None else ctx.base[:, 1]
            return hand_clearance(ctx, percept, pos + rot @ g.point, along, obj)

        preferred, chosen = grip(ctx, obj), chosen_grip(ctx, percept, obj)
        assert gap(preferred) < 0.0 <= GRASP_CLEARANCE <= gap(chosen)
        assert np.allclose(grasp_point(ctx, percept, obj), pos + rot @ chosen.point)
        ctx.failures[obj] = 1
        retry = chosen_grip(ctx, percept, obj)
        assert retry.axis != chosen.axis or np.linalg.norm(
            retry.point[:2] - chosen.point[:2]) >= RETRY_SHIFT  # fmt: skip
    finally:
        env.close()


def test_transit_keeps_clear_of_the_basket() -> None:
    """LIBERO-10 task 7, state 0: with the hand inside the basket (as after a place in
    it), on its way to the cream cheese box, it must first rise above the basket's rim;
    on its way into the basket, or over open table, nothing holds it up."""
    env, scene, percept, ctx = _living_room(7, 0)
    try:
        basket = percept.position("basket_1")
        rim = basket[2] + scene.extents["basket_1"][1][2]
        inside = replace(percept, tcp=basket + np.array([0.0, 0.0, 0.06]))
        cheese = percept.position("cream_cheese_1")[:2]
        assert transit_height(ctx, inside, cheese) == pytest.approx(rim + TRANSIT_CLEARANCE)
        assert transit_height(ctx, inside, basket[:2]) == -np.inf
        open_table = replace(percept, tcp=np.array([0.0, -0.35, 0.5]))
        assert transit_height(ctx, open_table, cheese) == -np.inf
    finally:
        env.close()


@pytest.mark.slow
def test_scripted_plan_puts_the_cream_cheese_in_the_basket(capsys) -> None:
    """LIBERO-10 task 7, initial state 0 (failed before the transit clearance: the hand,
    leaving the basket on a straight line down to the cream cheese box, dragged the basket
    onto the box): both objects into the basket within 520 steps, each pick the first
    time."""
    argv = ["--domain", "libero", "evaluate", "benchmark", "--suite", "libero_10", "--task",
            "7", "--init-states", "0:1", "--policy", "scripted-plan", "--json"]  # fmt: skip
    assert cli.main(argv) == 0
    (episode,) = json.loads(capsys.readouterr().out)["episode_log"]
    assert episode["success"], episode["trace"]
    assert not any("FAILED" in line for line in episode["trace"]), episode["trace"]
