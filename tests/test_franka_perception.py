"""FrankaKitchen-v1's perceptions: ``env`` reads only the env's own observation (through the
caller's wrappers) and the robot's kinematics; ``sim`` is the simulator's readout."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gymnasium_robotics")

import gymnasium as gym  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

from osg_control.errors import DomainError, EnvOptionError, UsageError  # noqa: E402
from osg_control.franka.arm import FrankaConfig  # noqa: E402
from osg_control.franka.compat import prepare  # noqa: E402
from osg_control.franka.domain import PERCEPTIONS, facts_of, franka_domain  # noqa: E402
from osg_control.franka.envs import make_franka_env  # noqa: E402
from osg_control.franka.perception import (  # noqa: E402
    ARM,
    GRASP_WIDTH,
    OBJECT_QPOS,
    REFERENCE_QUAT,
    width_grasp,
)
from osg_control.perception.spec import PerceptionSpec  # noqa: E402

CLOSE = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0])
MICROWAVE = 22 - 9 + OBJECT_QPOS.start
"""The microwave door's angle in the observation (qpos 22)."""


def canonical_quat(rotation: np.ndarray) -> np.ndarray:
    """A rotation's quaternion (w, x, y, z) by SciPy, in the hemisphere of the reset's."""
    x, y, z, w = Rotation.from_matrix(np.asarray(rotation).reshape(3, 3)).as_quat()
    quat = np.array([w, x, y, z])
    return -quat if quat @ np.array(REFERENCE_QUAT) < 0 else quat


def _fk(env, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return env.ik.tcp_pose(np.asarray(q, dtype=float))


def test_the_domain_supports_env_and_sim_with_env_the_default() -> None:
    assert PERCEPTIONS == ("env", "sim")
    assert FrankaConfig().perception == PerceptionSpec("env")
    assert franka_domain().perceptions == ("env", "sim")


def test_env_tcp_is_forward_kinematics_of_the_observed_joints_not_the_true_site() -> None:
    """With the env's robot noise raised 20x (+-2 cm rad per joint) the percept's TCP is
    centimetres off the true site and exactly the FK of the observation's joints."""
    env = make_franka_env(tasks=["microwave"], env_kwargs={"robot_noise_ratio": 0.2})
    obs, info = env.reset(seed=0)
    offsets = []
    for _ in range(6):
        percept = env.percept()
        observed = env.env_observation()
        np.testing.assert_array_equal(percept.joints, observed[ARM])
        pos, rot = _fk(env, observed[ARM])
        np.testing.assert_allclose(percept.state[:3], pos, atol=1e-12)
        np.testing.assert_allclose(percept.state[3:7], canonical_quat(rot), atol=1e-9)
        assert percept.state[9] == pytest.approx(observed[7:9].sum())
        np.testing.assert_array_equal(obs, percept.state)
        assert not np.shares_memory(env.observe(), percept.state)
        offsets.append(np.linalg.norm(percept.state[:3] - env.tcp_pose()[0]))
        obs, _r, _te, _tr, info = env.step(np.array([0.01, 0, 0, 0, 0, 0, 1.0]))
        assert info["percept"] is env.percept()
    assert min(offsets) > 1e-3, offsets
    env.close()
    # The env's own noise (ratio 0.01): joints within 1 mrad, the TCP within a few mm.
    quiet = make_franka_env(tasks=["microwave"])
    quiet.reset(seed=0)
    assert np.abs(quiet.percept().joints - quiet.arm_q).max() <= 1e-3 + 1e-12
    assert 0 < np.linalg.norm(quiet.percept().state[:3] - quiet.tcp_pose()[0]) < 0.005
    quiet.close()


def test_env_world_and_facts_come_from_the_observed_object_qpos() -> None:
    env = make_franka_env(tasks=["microwave"], env_kwargs={"object_noise_ratio": 0.05})
    env.reset(seed=1)
    for _ in range(3):
        percept = env.percept()
        observed = env.env_observation()
        np.testing.assert_array_equal(percept.world[:21], observed[OBJECT_QPOS])
        assert percept.world[21] == 0.0  # open hand: no grasp
        assert percept.facts == facts_of(percept.world)
        # Not the truth: the observation's object noise is in the percept.
        assert np.abs(percept.world[:21] - env.world_state()[:21]).max() > 0
        env.step(np.zeros(7))
    env.close()


class ShiftedObservation(gym.ObservationWrapper):
    """A user's wrapper: joint 1 seen 0.1 rad further, the microwave seen open."""

    def observation(self, observation):
        shifted = dict(observation)
        vector = np.array(observation["observation"], dtype=float)
        vector[0] += 0.1
        vector[MICROWAVE] = -0.75
        shifted["observation"] = vector
        return shifted


def test_a_users_observation_wrapper_is_seen_through() -> None:
    prepare()
    own = ShiftedObservation(gym.make("FrankaKitchen-v1", tasks_to_complete=["microwave"]))
    env = make_franka_env(env=own, tasks=["microwave"])
    env.reset(seed=0)
    percept = env.percept()
    assert percept.joints[0] == pytest.approx(env.arm_q[0] + 0.1, abs=2e-3)
    pos, _ = _fk(env, env.env_observation()[ARM])
    np.testing.assert_allclose(percept.state[:3], pos, atol=1e-12)
    assert np.linalg.norm(percept.state[:3] - env.tcp_pose()[0]) > 0.02
    # The robot believes what the wrapper shows; the simulator's truth is unchanged.
    assert "microwave-open" in percept.facts and "microwave-closed" in env.facts()
    env.close()
    plain = make_franka_env(tasks=["microwave"])
    plain.reset(seed=0)
    assert "microwave-closed" in plain.percept().facts
    plain.close()


class FlatObservation(gym.ObservationWrapper):
    def observation(self, observation):
        return np.asarray(observation["observation"], dtype=float)[:20]


def test_an_observation_without_the_59_entries_is_refused() -> None:
    prepare()
    own = FlatObservation(gym.make("FrankaKitchen-v1", tasks_to_complete=["microwave"]))
    env = make_franka_env(env=own, tasks=["microwave"])
    with pytest.raises(DomainError, match="59-D observation"):
        env.reset(seed=0)
    # The array itself (a wrapper that unpacks the dict) is read as it is.
    prepare()
    unpacked = gym.make("FrankaKitchen-v1", tasks_to_complete=["microwave"])
    unpacked = gym.wrappers.TransformObservation(
        unpacked, lambda o: np.asarray(o["observation"]), None
    )
    env = make_franka_env(env=unpacked, tasks=["microwave"])
    env.reset(seed=0)
    assert env.percept().state.shape == (10,)


def test_sim_is_todays_privileged_readout() -> None:
    """``sim``: the true site, the contact force, the true finger joints and object qpos."""
    env = make_franka_env(tasks=["microwave"], perception=PerceptionSpec("sim"))
    env.reset(seed=0)
    for action in (np.zeros(7), CLOSE, CLOSE):
        percept = env.percept()
        site = env.model.site("end_effector").id
        np.testing.assert_array_equal(percept.state[:3], env.data.site_xpos[site])
        np.testing.assert_allclose(
            percept.state[3:7], canonical_quat(env.data.site_xmat[site]), atol=1e-9
        )
        assert percept.state[8] == min(env.finger_forces())
        assert percept.state[9] == env.data.qpos[7:9].sum()
        np.testing.assert_array_equal(percept.joints, env.arm_q)
        np.testing.assert_array_equal(percept.world, env.world_state())
        np.testing.assert_array_equal(percept.world[:21], env.data.qpos[9:30])
        assert percept.facts == env.facts()
        env.step(action)
    env.close()


def test_env_grasp_and_force_come_from_the_fingers_not_contacts() -> None:
    """An empty hand closing is never a grasp (its fingers are still moving while they are
    wider than ``GRASP_WIDTH``): no ``holding``, no force; the rule itself."""
    env = make_franka_env(tasks=["microwave"])
    env.reset(seed=0)
    for _ in range(10):
        env.step(CLOSE)
        percept = env.percept()
        assert "hand-empty" in percept.facts and percept.state[8] == 0.0
    assert percept.state[9] < GRASP_WIDTH
    env.close()
    closed, still, moving = -1.0, np.zeros(2), np.array([0.1, 0.1])
    assert width_grasp(closed, np.array([0.022, 0.022]), still)
    assert not width_grasp(closed, np.array([0.022, 0.022]), moving)
    assert width_grasp(closed, np.array([0.022, 0.022]), moving, held=True)
    assert not width_grasp(closed, np.array([0.002, 0.002]), still, held=True)
    assert not width_grasp(1.0, np.array([0.022, 0.022]), still, held=True)


def test_bad_perceptions_are_refused() -> None:
    with pytest.raises(UsageError, match="unknown perception 'lidar'"):
        PerceptionSpec("lidar")
    with pytest.raises(EnvOptionError, match="supports the perceptions env, sim, not 'robot'"):
        FrankaConfig(perception=PerceptionSpec("robot"))
    with pytest.raises(EnvOptionError, match="must be a PerceptionSpec"):
        FrankaConfig(perception="env")  # type: ignore[arg-type]
    with pytest.raises(EnvOptionError, match="only 'env' takes tcp_noise"):
        FrankaConfig(perception=PerceptionSpec("sim", tcp_noise=0.02))
    with pytest.raises(EnvOptionError, match="joint_noise"):
        FrankaConfig(perception=PerceptionSpec("env", joint_noise=0.01))
    with pytest.raises(UsageError, match="does not support perception 'robot'"):
        make_franka_env(tasks=["microwave"], perception=PerceptionSpec("robot"))
    with pytest.raises(DomainError, match="env_kwargs may not set"):
        make_franka_env(tasks=["microwave"], env_kwargs={"tasks_to_complete": ["kettle"]})


def test_the_core_env_config_maps_onto_the_domains_perceptions() -> None:
    """The core's ``EnvConfig`` (collection, Table I): ``paper`` is the env's observation
    with the paper's TCP noise, ``sim`` the oracle."""
    from osg_control.environment.arm_env import EnvConfig
    from osg_control.franka.envs import franka_config

    assert franka_config(EnvConfig()).perception == PerceptionSpec("env")
    noisy = franka_config(EnvConfig(perception=PerceptionSpec("paper", tcp_noise=0.02)))
    assert noisy.perception == PerceptionSpec("env", tcp_noise=0.02)
    assert franka_config(EnvConfig(perception=PerceptionSpec("sim"))).perception.name == "sim"
    with pytest.raises(UsageError, match="supports: env, sim"):
        franka_config(EnvConfig(perception=PerceptionSpec("robot")))


@pytest.mark.slow
def test_benchmark_reports_its_perception_and_max_steps() -> None:
    from osg_control.domain.registry import get_domain
    from osg_control.evaluation.benchmark import format_benchmark, run_benchmark

    domain = get_domain("franka-kitchen")
    with pytest.raises(UsageError, match="does not support perception 'robot'"):
        run_benchmark(domain, episodes=1, perception=PerceptionSpec("robot"))
    with pytest.raises(UsageError, match="exact state: no --noise"):
        run_benchmark(domain, episodes=1, noise=0.02, perception=PerceptionSpec("sim"))
    summary = run_benchmark(
        domain, tasks=["light switch"], episodes=1, workers=1, perception=PerceptionSpec("sim")
    )
    assert summary["perception"]["name"] == "sim" and summary["oracle"] is True
    assert summary["max_steps"] == summary["steps"]["max"] <= 280
    assert "ORACLE" in format_benchmark(summary)
    default = run_benchmark(domain, tasks=["light switch"], episodes=1, workers=1)
    assert default["perception"] == PerceptionSpec("env").to_dict()
    assert default["oracle"] is False and default["task_rates"] == {"light switch": 1.0}
