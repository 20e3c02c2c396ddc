"""FrankaKitchen-v1's own Panda as a robot description: read from the env's MJCF, listed by
``osg robots``, its two models agreeing, and the adapter driving it through the core's IK
(the QP mink's ``solve_ik`` built from the adapter's former tasks)."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("gymnasium_robotics")

import mink  # noqa: E402
import qpsolvers  # noqa: E402

from osg_control import cli  # noqa: E402
from osg_control.control.ik import DiffIKController, IKConfig  # noqa: E402
from osg_control.control.rotations import rotation_step  # noqa: E402
from osg_control.errors import ModelNotFoundError  # noqa: E402
from osg_control.franka.envs import make_franka_env  # noqa: E402
from osg_control.robots import registry  # noqa: E402
from osg_control.robots.franka_kitchen_panda import RESET_Q  # noqa: E402
from osg_control.robots.registry import get_robot  # noqa: E402

NAME = "franka-kitchen-panda"


@pytest.fixture(scope="module")
def adapter():
    env = make_franka_env(tasks=["microwave"])
    yield env
    env.close()


def test_osg_robots_lists_the_kitchen_panda(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["robots", "--json"]) == 0
    listed = {entry["name"]: entry for entry in json.loads(capsys.readouterr().out)}
    entry = listed[NAME]
    assert entry["joints"] == [f"robot:panda0_joint{i}" for i in range(1, 8)]
    assert entry["tcp"] == {"body": "panda0_link7", "frame": "end_effector", "site": "end_effector"}
    # The env's mount (0, 0, 1.8), yaw 90 degrees; no force sensor in its observation.
    assert entry["mount"]["position"] == [0.0, 0.0, 1.8]
    assert entry["sensors"] == ["encoders", "finger_width"] and entry["control_hz"] == 12.5
    assert entry["lower"][5] == 0.0 and entry["upper"][3] == pytest.approx(-0.4)


def test_without_gymnasium_robotics_it_is_not_listed_and_names_the_extra(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Its models are the library's files: where the ``franka`` extra is not installed,
    ``osg robots`` leaves it out and asking for it names the extra."""
    monkeypatch.setattr(registry, "_installed", lambda package: False)
    monkeypatch.setattr(registry, "_LOADED", {})
    assert NAME not in registry.robot_names() and "panda" in registry.robot_names()
    with pytest.raises(ModelNotFoundError, match=r"pip install 'osg-control\[franka\]'"):
        get_robot(NAME)


def test_the_description_is_the_envs_arm(adapter) -> None:
    """Its home is the env's reset posture held within the limits (joint 2 starts 5.7 mrad
    past its MJCF range); the adapter's IK is the core's, on this description, drawn to the
    env's own reset posture."""
    robot = adapter.robot
    assert robot is get_robot(NAME)
    np.testing.assert_array_equal(RESET_Q, adapter.kitchen.robot_env.init_qpos[:7])
    assert RESET_Q[1] < robot.arm.lower[1] == robot.home_q[1]
    assert isinstance(adapter.ik, DiffIKController) and adapter.ik.robot is robot
    np.testing.assert_array_equal(adapter.ik.posture, RESET_Q)


def test_mujoco_and_pinocchio_models_agree() -> None:
    """Both models are built from one compiled MJCF (``control.mujoco_pinocchio``): the TCP
    pose to 1e-12 anywhere (rounding; ``pinocchio.buildModelFromMJCF`` on the spec's
    ``to_xml`` was 1.4e-6 off, its 6 significant digits)."""
    robot = get_robot(NAME)
    mink_ik = DiffIKController(robot, IKConfig(backend="mink"))
    pin_ik = DiffIKController(robot, IKConfig(backend="pinocchio"))
    rng = np.random.default_rng(0)
    lower, upper = np.array(robot.arm.lower), np.array(robot.arm.upper)
    for _ in range(20):
        q = rng.uniform(lower, upper)
        (p1, r1), (p2, r2) = mink_ik.tcp_pose(q), pin_ik.tcp_pose(q)
        np.testing.assert_allclose(p1, p2, rtol=0, atol=1e-12)
        np.testing.assert_allclose(r1, r2, rtol=0, atol=1e-12)


def test_the_adapters_ik_solves_minks_qp_of_the_former_arm_ik(adapter) -> None:
    """The core IK with the adapter's configuration (``FrankaConfig.ik_config``) solves the
    QP that ``mink.solve_ik`` solved for the adapter before (frame task, posture task toward
    the env's reset, configuration limits at gain 0.5, no speed limit), to 1e-5 rad/s."""
    config = adapter.config
    model = adapter.ik.backend.model
    configuration = mink.Configuration(model)
    frame = mink.FrameTask(
        "end_effector",
        "site",
        position_cost=config.position_cost,
        orientation_cost=config.orientation_cost,
        lm_damping=1e-6,
    )
    posture = mink.PostureTask(model, cost=config.posture_cost)
    posture.set_target(adapter.posture)
    limits = [mink.ConfigurationLimit(model, gain=config.limit_gain)]
    rng = np.random.default_rng(1)
    lower, upper = adapter.ik.backend.lower, adapter.ik.backend.upper
    for _ in range(30):
        q = np.clip(adapter.posture + rng.normal(0.0, 0.3, 7), lower, upper)
        pos, rot = adapter.ik.tcp_pose(q)
        target = pos + rng.uniform(-0.04, 0.04, 3)
        turned = rotation_step(rot, rng.uniform(-0.2, 0.2, 3))
        configuration.update(q)
        goal = mink.SE3.from_rotation_and_translation(mink.SO3.from_matrix(turned), target)
        frame.set_target(goal)
        expected = mink.solve_ik(
            configuration, [frame, posture], adapter.dt, "daqp", damping=1e-9, limits=limits
        )
        ours = adapter.ik.solve_velocity(q, target, turned)
        np.testing.assert_allclose(ours, expected, rtol=0, atol=1e-5)
    assert "daqp" in qpsolvers.available_solvers


def test_run_refuses_a_video_camera_the_env_cannot_film_from(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The adapter's frames are the library env's own render: ``--video-camera`` is refused
    (exit 2) rather than ignored."""
    argv = ["--domain", "franka-kitchen", "run", "--goal", "microwave-open"]
    argv += ["--video-camera", "overview", "--episodes", "1"]
    assert cli.main(argv) == 2
    assert "FrankaKitchenAdapter renders its own view" in capsys.readouterr().err
