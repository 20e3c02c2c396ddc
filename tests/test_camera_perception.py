"""The ``camera`` perception: object poses from rendered RGB + depth (real MuJoCo renders).

Needs an OpenGL back end (``MUJOCO_GL=egl`` or ``osmesa``); skipped without one.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from osg_control.cli import main
from osg_control.environment.arm_env import EnvConfig
from osg_control.errors import EnvOptionError, UsageError
from osg_control.kitchen.env import KitchenEnv
from osg_control.perception.camera import CameraSetup, back_project
from osg_control.perception.spec import CAMERA_EVERY, CAMERA_SIZE, PerceptionSpec, perception_spec

mujoco = pytest.importorskip("mujoco")
try:
    _probe = mujoco.Renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 8, 8)
    _probe.close()
except Exception as err:  # noqa: BLE001 - any GL failure means no back end here
    pytest.skip(f"no OpenGL back end ({err}); set MUJOCO_GL=egl", allow_module_level=True)

CUBE = slice(2, 5)
"""The cube's position in the kitchen's world vector."""


def _camera_env(**config) -> KitchenEnv:
    return KitchenEnv(config=EnvConfig(perception=perception_spec("camera"), **config))


def _blind(env: KitchenEnv) -> None:
    """Blank every image the env's cameras render (black RGB, depth at the far plane)."""
    env.sense()  # makes the rig
    assert env.cameras is not None
    render = env.cameras.rig.render

    def blank(data, index, wants_depth):
        rgb, depth = render(data, index, lambda rgb: wants_depth(np.zeros_like(rgb)))
        return np.zeros_like(rgb), None if depth is None else np.zeros_like(depth)

    env.cameras.rig.render = blank  # type: ignore[method-assign]


def test_back_projection_inverts_the_pinhole() -> None:
    """A point on a camera's axis maps to the image centre and back."""
    setup = CameraSetup("c", 320, 240, 45.0, np.array([0.0, 0.0, 1.0]), np.eye(3))
    point = back_project(setup, np.array([119.5]), np.array([159.5]), np.array([0.7]))
    np.testing.assert_allclose(point[0], [0.0, 0.0, 0.3], atol=1e-12)
    assert setup.intrinsics[0, 0] == pytest.approx(120 / np.tan(np.radians(22.5)))


def test_the_estimate_is_within_5_mm_on_random_placements() -> None:
    """Eight placements over the cube's region: each estimate within 5 mm of the truth."""
    env = _camera_env()
    rng = np.random.default_rng(7)
    errors = []
    for seed in range(8):
        x, y = rng.uniform([0.40, -0.30], [0.60, -0.10])
        env.reset(seed=seed, options={"world": {"cube_pos": [x, y, 0.0225]}})
        estimate, truth = env.percept().world[CUBE], env.world_state()[CUBE]
        errors.append(float(np.linalg.norm(estimate - truth)))
    assert max(errors) < 0.005, errors
    assert "cube-on-counter" in env.percept().facts


def test_three_cubes_each_located_by_its_colour_within_5_mm() -> None:
    """Three cubes placed at random, 9 cm or more apart: each cube's mask is its own
    colour's, and each estimate is within 5 mm of that cube's truth, never another's."""
    env = KitchenEnv(config=EnvConfig(perception=perception_spec("camera")), cubes=3)
    fields = {name: i for i, name in enumerate(env.world_sensors)}
    assert env.camera_perception is not None
    assert [t.name for t in env.camera_perception.targets] == ["cube", "cube2", "cube3"]
    rng = np.random.default_rng(3)
    errors = []
    for seed in range(4):
        places: list[np.ndarray] = []
        while len(places) < 3:
            xy = rng.uniform([0.40, -0.30], [0.60, -0.10])
            if all(np.linalg.norm(xy - other) >= 0.09 for other in places):
                places.append(xy)
        names = ("cube", "cube2", "cube3")
        world = {f"{p}_pos": [*xy, 0.0225] for p, xy in zip(names, places, strict=True)}
        env.reset(seed=seed, options={"world": world})
        seen, truth = env.percept().world, env.world_state()
        for prefix in ("cube", "cube2", "cube3"):
            at = [fields[f"{prefix}_{axis}"] for axis in "xyz"]
            errors.append(float(np.linalg.norm(seen[at] - truth[at])))
    assert max(errors) < 0.005, errors
    facts = env.percept().facts
    assert {"cube-on-counter", "(on-counter cube-2)", "(on-counter cube-3)"} <= facts


def test_the_camera_renders_at_its_rate_and_at_decision_points() -> None:
    env = _camera_env(max_steps=None)
    env.reset(seed=0)
    assert env.cameras is not None
    renders = env.cameras.renders
    for _ in range(2 * CAMERA_EVERY):
        env.step(np.zeros(7))
    assert env.cameras.renders - renders == 2
    env.sense()  # a decision point renders whatever the rate
    assert env.cameras.renders - renders == 3


def test_blank_images_give_no_estimate_and_the_stack_does_not_lift(capsys) -> None:
    """Blind: no cube estimate, no cube fact, and the executor stops with a named failure."""
    from osg_control.execution.executor import load_executor
    from osg_control.kitchen.domain import kitchen_domain

    env = _camera_env(max_steps=None)
    env.reset(seed=0)
    _blind(env)
    env.reset(seed=0)  # every image of the episode blank
    percept = env.percept()
    assert np.isnan(percept.world[CUBE]).all()
    assert not {"cube-on-counter", "cube-lifted", "holding-cube"} & percept.facts
    executor = load_executor(kitchen_domain(), max_replans=2)
    result = executor.execute(["cube-lifted"], env, env.observe())
    assert not result.success
    assert result.failure is not None and "no plan" in result.failure
    assert "cube-lifted" not in env.facts()


def test_an_occluded_cube_keeps_its_last_estimate_and_its_age() -> None:
    env = _camera_env(max_steps=None)
    env.reset(seed=0)
    seen = env.percept().world[CUBE].copy()
    _blind(env)
    for _ in range(CAMERA_EVERY + 1):
        _obs, _r, _t, _tr, info = env.step(np.zeros(7))
    np.testing.assert_array_equal(env.percept().world[CUBE], seen)
    assert info["camera"]["pixels"]["cube"] == 0
    age = (CAMERA_EVERY + 1) / 20.0
    assert info["camera"]["age_s"]["cube"] == pytest.approx(age, abs=1e-6)
    assert "cube-on-counter" in env.percept().facts


def test_a_held_cube_moves_with_the_hand_when_out_of_sight() -> None:
    """Held and unseen, the estimate follows the perceived TCP: the grasp stays perceived."""
    env = _camera_env(max_steps=None)
    env.reset(seed=0, options={"node": "cube-lifted", "holding": "cube"})
    assert "holding-cube" in env.percept().facts
    _blind(env)
    for _ in range(10):
        env.step(np.array([0.0, 0.0, 0.01, 0.0, 0.0, 0.0, -1.0]))  # up 10 cm, hand shut
    percept = env.percept()
    assert "holding-cube" in percept.facts
    assert np.linalg.norm(percept.world[CUBE] - env.world_state()[CUBE]) < 0.02


def test_camera_spec_and_refusals() -> None:
    spec = perception_spec("camera")
    assert (spec.image_width, spec.image_height) == CAMERA_SIZE
    assert spec.camera_every == CAMERA_EVERY
    with pytest.raises(UsageError, match="needs a rate and an image size"):
        PerceptionSpec("camera")
    with pytest.raises(UsageError, match="--noise is the paper protocol"):
        perception_spec("camera", 0.02)


def test_a_scene_without_cameras_is_refused_by_name(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("osg_control.kitchen.env.kitchen_cameras", lambda cubes: None)
    with pytest.raises(
        EnvOptionError, match="simulates the perceptions paper, robot, sim, not 'camera'"
    ):
        KitchenEnv(config=EnvConfig(perception=perception_spec("camera")))


def test_the_cli_accepts_camera_and_records_it_in_json(capsys) -> None:
    argv = ["run", "--goal", "cube-lifted", "--start", "home", "--perception", "camera", "--json"]
    assert main(argv) == 0
    payload = json.loads(capsys.readouterr().out)
    perception = payload["perception"]
    assert perception["name"] == "camera"
    assert perception["camera_every"] == CAMERA_EVERY
    assert [perception["image_width"], perception["image_height"]] == list(CAMERA_SIZE)
    assert [c["name"] for c in payload["cameras"]] == ["counter_cam", "cabinet_cam"]
    assert payload["episodes"][0]["scored_success"] is True


def test_run_refuses_an_unknown_video_camera(capsys) -> None:
    argv = ["run", "--goal", "cube-lifted", "--video-camera", "nowhere", "--perception", "camera"]
    assert main(argv) == 2
    assert "counter_cam" in capsys.readouterr().err


def test_a_lost_grasp_makes_the_cameras_look_where_the_cube_fell() -> None:
    """The cube knocked out of the hand: the grasp is lost, and the next step renders (off
    the rate) and finds the cube where it lies, so a replan starts from there."""
    from osg_control.kitchen.disturbances import displace_cube

    env = _camera_env(max_steps=None)
    env.reset(seed=0, options={"node": "cube-grasped", "holding": "cube"})
    assert "holding-cube" in env.percept().facts
    displace_cube(env, np.array([0.05, 0.0]))
    renders = env.cameras.renders
    shut = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0])
    for _ in range(3):
        env.step(shut)
    assert "holding-cube" not in env.percept().facts
    assert env.cameras.renders > renders
    assert np.linalg.norm(env.percept().world[CUBE] - env.world_state()[CUBE]) < 0.005
    assert "cube-on-counter" in env.percept().facts


def test_a_cube_unseen_at_the_start_is_pursued_after_the_part_of_the_goal_within_reach() -> None:
    """Cube 2 hidden from the cameras' first look (its colour blanked): the whole goal has
    no plan from the first percept, so the executor runs the part within reach (the door,
    cube 1), which the cameras see cube 2 during, then replans the whole and finishes."""
    from osg_control.domain.registry import get_domain
    from osg_control.execution.executor import load_executor, task_env_config
    from osg_control.kitchen.cameras import cube_target
    from osg_control.perception.colour_pose import colour_mask

    kitchen = get_domain("kitchen")
    task = kitchen.task("two-cubes-in-cabinet")
    scene = kitchen.for_task(task)
    env = scene.make_env(config=task_env_config(perception_spec("camera")))
    env.sense()  # makes the rig
    rig, hiding = env.cameras.rig, [True]
    render = rig.render

    def cube_2_hidden(data, index, wants_depth):
        def masked(rgb):
            if hiding[0]:
                rgb = rgb.copy()
                rgb[colour_mask(rgb, cube_target(2)) > 0] = 0
            return wants_depth(rgb)

        return render(data, index, masked)

    rig.render = cube_2_hidden  # type: ignore[method-assign]
    obs, _ = env.reset(seed=7, options={"facts": task.world})
    hiding[0] = False
    assert "(on-counter cube-2)" not in env.percept().facts
    plans = []
    executor = load_executor(scene, max_replans=2)
    executor.on_event = lambda kind, fields: plans.append(fields["plan"]) if kind == "plan" else 0
    result = executor.execute(task.goal, env, obs)
    assert result.success and set(task.goal) <= env.facts(), result.to_dict()
    assert result.replans == 2 and plans[0] == [] and len(plans) == 3
    assert not any("cube-2" in step for step in plans[1]), plans[1]  # door and cube 1
    assert any("cube-2" in step for step in plans[2]), plans[2]  # then cube 2


def test_a_rim_seen_without_its_top_is_moved_half_the_box_away_from_the_camera() -> None:
    from osg_control.perception.colour_pose import _edge_shift

    grid = np.stack(np.meshgrid(np.linspace(0, 0.045, 10), np.linspace(0, 0.045, 10)), -1)
    face = grid.reshape(-1, 2)
    np.testing.assert_array_equal(_edge_shift(face, np.array([1.0, 0.0]), 0.0225), [0, 0])
    rim = np.stack([np.zeros(10), np.linspace(0, 0.045, 10)], 1)  # an edge along y
    shift = _edge_shift(rim, np.array([-1.0, 0.1]), 0.0225)  # camera on the +x side
    np.testing.assert_allclose(shift, [-0.0225, 0.0], atol=1e-9)


@pytest.mark.slow
def test_camera_episodes_run_in_forked_workers(tmp_path) -> None:
    """The CLI's GL check renders in a child process: a context made in the parent made
    every forked worker's renderer hang (EGL does not survive a fork). Run as its own
    process: this test process has a GL context already (the module's check above)."""
    import os
    import subprocess
    import sys

    argv = ["evaluate", "tasks", "--task", "pick-up", "--episodes", "1", "--perception",
            "camera", "--workers", "2", "--replans", "2", "--json"]  # fmt: skip
    run = subprocess.run(
        [sys.executable, "-c", "import sys; from osg_control.cli import main; "
         "sys.exit(main(sys.argv[1:]))", *argv],
        env={**os.environ, "OSG_CACHE_DIR": str(tmp_path)},
        capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip
    assert run.returncode in (0, 1), run.stderr[-2000:]
    assert json.loads(run.stdout)["perception"]["name"] == "camera"


@pytest.mark.parametrize("flag", [["--video", "VIDEO"], ["--perception", "camera"]])
def test_no_gl_back_end_is_a_usage_error_naming_mujoco_gl(flag, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("MUJOCO_GL", "no-such-back-end")
    argv = ["run", "--goal", "door-open", *[str(tmp_path / "v.mp4") if f == "VIDEO" else f
                                            for f in flag]]  # fmt: skip
    assert main(argv) == 2
    assert "no OpenGL back end" in capsys.readouterr().err
    assert not (tmp_path / "v.mp4").exists()
