"""robosuite's Panda as a robot description, and our IK driving it through robosuite's
JOINT_POSITION controller in a LIBERO scene (the ``libero`` extra; skipped without it)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from osg_control.control.ik import DiffIKController  # noqa: E402
from osg_control.control.ik_backends import IKConfig  # noqa: E402
from osg_control.control.robot_model import check_models  # noqa: E402
from osg_control.libero.drive import (  # noqa: E402
    CAREFUL_DELTA,
    JOINTS_OBS,
    TURN_STEP,
    JointTargetDriver,
)
from osg_control.libero.env import CONTROL_HZ, JOINT_DELTA_LIMIT, JOINT_KP, LiberoEnv  # noqa: E402
from osg_control.libero.robot import libero_panda, mounted_panda  # noqa: E402


@pytest.fixture(scope="module")
def soup_env():
    env = LiberoEnv("libero_10", 0)
    yield env
    env.close()


def test_description_matches_its_models() -> None:
    robot = libero_panda()
    check_models(robot)  # joints, limits, TCP body and frame, fingers, in both models
    assert robot.n_joints == 7 and robot.redundant
    assert robot.arm.upper[3] == pytest.approx(-0.0698) and robot.arm.effort[6] == 12.0


@pytest.mark.parametrize("backend", ["mink", "pinocchio"])
def test_forward_kinematics_is_the_scenes_grip_site(soup_env: LiberoEnv, backend: str) -> None:
    """At three initial states, our FK of the observed joints (the robot at the scene's
    mount) is where LIBERO observes its end effector, and the TCP approaches downward."""
    for state in (0, 1, 2):
        obs = soup_env.reset(state)
        ik = DiffIKController(mounted_panda(soup_env.sim), IKConfig(backend=backend))
        position, rotation = ik.tcp_pose(obs["robot0_joint_pos"])
        np.testing.assert_allclose(position, obs["robot0_eef_pos"], atol=1e-9)
        assert rotation[2, 2] < -0.99


def test_ik_reaches_above_an_observed_object(soup_env: LiberoEnv) -> None:
    """A scripted reach to 10 cm above the alphabet soup, from the observation only."""
    obs = soup_env.reset(0)
    driver = JointTargetDriver(mounted_panda(soup_env.sim))
    _, rotation = driver.tcp_pose(obs[JOINTS_OBS])
    target = obs["alphabet_soup_1_pos"] + np.array([0.0, 0.0, 0.10])
    start = np.linalg.norm(obs["robot0_eef_pos"] - target)
    for _ in range(80):
        action = driver.action(obs[JOINTS_OBS], target, rotation)
        assert np.all(np.abs(action) <= 1.0)
        obs = soup_env.step(action)
    assert start > 0.15
    assert np.linalg.norm(obs["robot0_eef_pos"] - target) < 0.005


def test_controller_takes_the_panda_speed_over_a_step(soup_env: LiberoEnv) -> None:
    """Every reset rebuilds robosuite's controller with our stiffness and the scale of the
    Panda's fastest joint over one step (robosuite's default 0.05 rad capped the arm)."""
    assert JOINT_DELTA_LIMIT == pytest.approx(max(libero_panda().arm.velocity) / CONTROL_HZ)
    for state in (0, 1):
        soup_env.reset(state)
        controller = soup_env.env.env.robots[0].controller
        np.testing.assert_allclose(controller.output_max, JOINT_DELTA_LIMIT)
        np.testing.assert_allclose(controller.output_min, -JOINT_DELTA_LIMIT)
        np.testing.assert_allclose(controller.kp, JOINT_KP)
        np.testing.assert_allclose(controller.kd, 2.0 * np.sqrt(JOINT_KP))


def test_driver_paces_transit_and_careful_legs() -> None:
    """A far target: a transit step takes a joint to its own speed limit over the step,
    past the careful pace, and none past its limit; a careful step stays within
    ``CAREFUL_DELTA``. A transit turn is told ``TURN_STEP`` at a time, so the hand turning
    in place holds its position."""
    robot = libero_panda()
    driver = JointTargetDriver(robot)
    q = np.array(robot.home_q)
    pos, rot = driver.tcp_pose(q)
    limits = np.array(robot.arm.velocity) / CONTROL_HZ
    fast = driver.action(q, pos + np.array([0.3, 0.2, -0.2]), rot, transit=True)[:7]
    careful = driver.action(q, pos + np.array([0.3, 0.2, -0.2]), rot)[:7]
    fast, careful = fast * JOINT_DELTA_LIMIT, careful * JOINT_DELTA_LIMIT
    assert np.all(np.abs(fast) <= limits + 1e-9) and np.max(np.abs(fast)) > CAREFUL_DELTA
    assert np.max(np.abs(careful)) <= CAREFUL_DELTA + 1e-9
    turned = rot @ np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90 deg
    step = driver.action(q, pos, turned, transit=True)[:7] * JOINT_DELTA_LIMIT
    moved, now = driver.tcp_pose(q + step)
    assert np.linalg.norm(moved - pos) < 0.002
    angle = np.arccos(np.clip((np.trace(rot.T @ now) - 1.0) / 2.0, -1.0, 1.0))
    assert TURN_STEP * 0.9 < angle <= TURN_STEP + 1e-6


def test_reach_tool_reports_its_figures() -> None:
    """``tools/libero_reach.py`` (the figures in docs/libero.md) runs and reports them."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    done = subprocess.run(
        [sys.executable, "tools/libero_reach.py", "--init-states", "0:1", "--steps", "5",
         "--json"],
        cwd=Path(__file__).resolve().parents[1], capture_output=True, text=True, timeout=600,
        check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    (row,) = json.loads(done.stdout)["reaches"]
    assert row["init_state"] == 0 and row["start_distance_m"] > 0.15 and row["ik_ms_mean"] > 0
    assert row["steps_to_1cm"] is None  # 5 steps are too few to get there
