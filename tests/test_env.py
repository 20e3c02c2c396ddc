"""KitchenEnv on the real simulator: API contract, physics sanity, resets, failures."""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Iterator
from pathlib import Path

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from osg_control.control.ik import IKConfig, joint_reset_controller
from osg_control.control.rotations import rotation_error
from osg_control.domain.spaces import OBS_DIM
from osg_control.environment.arm_env import EnvConfig
from osg_control.kitchen.domain import kitchen_domain
from osg_control.kitchen.env import KitchenEnv
from osg_control.kitchen.skills import NODES, TOP_DOWN_QUAT
from osg_control.kitchen.world import CUBE_HALF_SIZE, world_facts, world_state_from_array
from osg_control.perception.spec import PerceptionSpec
from osg_control.robots.panda import PANDA

ZERO_ACTION = np.zeros(7)


@pytest.fixture(scope="module")
def log_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Where MuJoCo may write ``MUJOCO_LOG.TXT`` (it logs to the working directory)."""
    return tmp_path_factory.mktemp("mujoco_log")


@pytest.fixture(scope="module")
def env(log_dir: Path) -> Iterator[KitchenEnv]:
    with contextlib.chdir(log_dir):
        kitchen = KitchenEnv()
    yield kitchen
    kitchen.close()


@pytest.fixture
def in_log_dir(log_dir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(log_dir)


def top_down_rotation() -> np.ndarray:
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, np.array(TOP_DOWN_QUAT, dtype=float))
    return rot.reshape(3, 3)


# ------------------------------------------------------------------ Gymnasium contract
def test_check_env_passes(env: KitchenEnv, in_log_dir: None) -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped, skip_render_check=True)
    # The observation is unbounded by design (positions, forces); everything else is clean.
    unexpected = [str(w.message) for w in caught if "infinity" not in str(w.message)]
    assert not unexpected


def test_spaces(env: KitchenEnv) -> None:
    obs, _ = env.reset(seed=0)
    assert obs.shape == (OBS_DIM,) and obs.dtype == env.observation_space.dtype
    assert env.observation_space.contains(obs)
    assert isinstance(env.action_space, gym.spaces.Box)
    np.testing.assert_array_equal(env.action_space.high, kitchen_domain().action_bounds)


# ------------------------------------------------------------------ physics sanity
def test_cube_stays_put_when_idle(env: KitchenEnv) -> None:
    env.reset(seed=0)
    cube_start = np.array(env.world().cube_pos)
    tcp_start, _ = env.tcp_pose()
    for _ in range(200):  # 10 s at 20 Hz
        env.step(ZERO_ACTION)
    assert np.linalg.norm(np.array(env.world().cube_pos) - cube_start) < 1e-3
    tcp_end, _ = env.tcp_pose()
    assert np.linalg.norm(tcp_end - tcp_start) < 2e-3


def test_door_only_slides(env: KitchenEnv) -> None:
    env.reset(seed=0)
    door = env.model.body("door").id
    start_pos = env.data.xpos[door].copy()
    start_quat = env.data.xquat[door].copy()
    y_positions = [start_pos[1]]
    try:
        # Push along +y, and also off-axis: forces along x and z and a torque.
        env.data.xfrc_applied[door] = [15.0, 10.0, -20.0, 3.0, -3.0, 3.0]
        for _ in range(6):
            env.step(ZERO_ACTION)
            np.testing.assert_allclose(env.data.xpos[door][[0, 2]], start_pos[[0, 2]], atol=1e-9)
            np.testing.assert_allclose(env.data.xquat[door], start_quat, atol=1e-9)
            y_positions.append(env.data.xpos[door][1])
    finally:
        env.data.xfrc_applied[door] = 0.0
    assert np.all(np.diff(y_positions) > 0)
    travel = y_positions[-1] - y_positions[0]
    assert 0.05 < travel < 0.4  # moving, not yet at the end of its 0.45 m slide
    assert env.world().door_opening == pytest.approx(travel, abs=2e-3)


# ------------------------------------------------------------------ actions
@pytest.mark.parametrize(
    "action",
    [
        np.full(7, np.nan),
        np.array([0.0, 0.0, np.inf, 0.0, 0.0, 0.0, 0.0]),
        np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -np.inf]),
        np.zeros(6),
        np.zeros(8),
        np.zeros((1, 7)),
    ],
    ids=["nan", "inf", "minus-inf-gripper", "short", "long", "2d"],
)
def test_bad_action_raises_and_leaves_actuators(env: KitchenEnv, action: np.ndarray) -> None:
    env.reset(seed=0)
    env.step(np.array([0.01, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]))  # non-trivial controls
    ctrl, qpos, time = env.data.ctrl.copy(), env.data.qpos.copy(), env.data.time
    with pytest.raises(ValueError):
        env.step(action)
    np.testing.assert_array_equal(env.data.ctrl, ctrl)
    np.testing.assert_array_equal(env.data.qpos, qpos)
    assert env.data.time == time


def test_actions_beyond_bounds_are_clipped(env: KitchenEnv) -> None:
    env.reset(seed=0)
    action = np.array([0.5, -0.5, 0.03, 1.0, -0.2, 0.05, 5.0])
    *_, info = env.step(action)
    np.testing.assert_array_equal(info["action_applied"], [0.02, -0.02, 0.02, 0.1, -0.1, 0.05, 1.0])
    inside = np.array([0.01, 0.0, -0.01, 0.02, 0.0, 0.0, 0.0])
    *_, info = env.step(inside)
    np.testing.assert_array_equal(info["action_applied"], inside)


# ------------------------------------------------------------------ resets
def test_seeded_reset_is_deterministic(env: KitchenEnv) -> None:
    options = {"radius": 0.1, "angle": 0.1}
    first, _ = env.reset(seed=3, options=options)
    env.step(np.array([0.01, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0]))
    second, _ = env.reset(seed=3, options=options)
    np.testing.assert_array_equal(first, second)
    other, _ = env.reset(seed=4, options=options)
    assert not np.array_equal(first, other)


def test_observation_noise_changes_only_position(env: KitchenEnv, log_dir: Path) -> None:
    with contextlib.chdir(log_dir):
        noisy = KitchenEnv(config=EnvConfig(perception=PerceptionSpec(tcp_noise=0.01)))
    try:
        for seed in range(3):
            clean_obs, _ = env.reset(seed=seed)
            noisy_obs, _ = noisy.reset(seed=seed)
            np.testing.assert_array_equal(noisy.tcp_pose()[0], env.tcp_pose()[0])
            np.testing.assert_array_equal(noisy_obs[3:], clean_obs[3:])
            assert np.all(noisy_obs[:3] != clean_obs[:3])
            assert np.all(np.abs(noisy_obs[:3] - clean_obs[:3]) < 0.06)  # 6 sigma
            clean_obs, *_ = env.step(ZERO_ACTION)
            noisy_obs, *_ = noisy.step(ZERO_ACTION)
            np.testing.assert_array_equal(noisy_obs[3:], clean_obs[3:])
            assert np.all(noisy_obs[:3] != clean_obs[:3])
    finally:
        noisy.close()


@pytest.mark.parametrize("node", ["home", "above-cube"])
def test_random_starts_stay_within_radius_and_angle(env: KitchenEnv, node: str) -> None:
    centre = np.array(NODES[node].position)
    top_down = top_down_rotation()
    for seed in range(8):
        obs, _ = env.reset(seed=seed, options={"node": node, "radius": 0.15, "angle": 0.2})
        pos, rot = env.tcp_pose()
        assert np.linalg.norm(pos - centre) <= 0.15 + 2e-3
        assert np.linalg.norm(rotation_error(top_down, rot)) <= 0.2 * np.sqrt(3) + 0.01
        np.testing.assert_allclose(obs[:3], pos)


def test_world_state_at_start(env: KitchenEnv) -> None:
    _, info = env.reset(seed=0)
    world = env.world()
    assert abs(world.door_opening) < 1e-6 and not world.door_open
    assert abs(world.valve_angle) < 1e-6
    np.testing.assert_allclose(world.cube_pos, (0.50, -0.20, CUBE_HALF_SIZE), atol=1e-3)
    assert world.cube_on_counter and not world.cube_in_cabinet and not world.cube_lifted
    assert not world.cube_grasped and not world.handle_grasped
    assert world_facts(world) == {"door-closed", "hand-empty", "cube-on-counter", "valve-closed"}
    assert info["world_facts"] == sorted(world_facts(world))
    assert world_state_from_array(world.as_array()) == world


# ------------------------------------------------------------------ failures
def test_diverged_physics_terminates_with_reason(env: KitchenEnv, in_log_dir: None) -> None:
    arm_dof = env.model.joint("panda_joint2").dofadr[0]
    for value in (np.nan, 1e12):
        env.reset(seed=0)
        env.data.qvel[arm_dof] = value
        obs, reward, terminated, _, info = env.step(ZERO_ACTION)
        assert terminated and reward == 0.0
        assert "diverged" in info["failure"] and "BADQVEL" in info["failure"]
        assert np.all(np.isfinite(obs))


# ------------------------------------------------------------------ joint reset
def test_joint_reset_in_sim(env: KitchenEnv) -> None:
    env.reset(seed=0)
    posture = env.ik.posture
    pos, rot = env.tcp_pose()
    # Park the arm elsewhere on the self-motion manifold of this TCP pose.
    away = np.array(PANDA.home_q) + np.array([0.6, 0.0, -0.6, 0.0, 0.4, 0.0, -0.4])
    pusher = joint_reset_controller(PANDA, IKConfig(posture=tuple(away)))
    q = env.arm_q
    for _ in range(40):
        q = pusher.reset_step(q, pos, rot)
    arm_qpos = [env.model.joint(f"panda_joint{i}").qposadr[0] for i in range(1, 8)]
    arm_act = [env.model.actuator(f"panda_joint{i}").id for i in range(1, 8)]
    env.data.qpos[arm_qpos] = q
    env.data.ctrl[arm_act] = q
    env.data.qvel[:] = 0.0
    mujoco.mj_forward(env.model, env.data)
    start_pos, start_rot = env.tcp_pose()
    start_distance = float(np.abs(env.arm_q - posture).max())
    assert start_distance > 0.3

    steps = env.joint_reset()

    end_pos, end_rot = env.tcp_pose()
    assert 1 <= steps < 40  # moved, and stopped on convergence before its budget
    assert float(np.abs(env.arm_q - posture).max()) < start_distance - 0.15
    # The servos track the null-space motion with a small lag: a few mm at most.
    assert np.linalg.norm(end_pos - start_pos) < 4e-3
    assert np.linalg.norm(rotation_error(start_rot, end_rot)) < 0.01
