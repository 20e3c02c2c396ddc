"""The envs refuse input that means nothing and end on a non-finite state, in both domains:
configuration fields out of range, unknown or contradictory reset options, actions that are
not 7 real numbers, and a NaN arm joint (an episode's named failure, never an exception out
of the executor). Also the joint drive's speed saturation on the real simulator."""

from __future__ import annotations

import warnings

import mujoco
import numpy as np
import pytest

from osg_control.control.servo import saturate_joint_speeds
from osg_control.domain.registry import get_domain
from osg_control.environment.arm_env import EnvConfig
from osg_control.errors import EnvOptionError, SimulationError
from osg_control.evaluation.joint_speeds import FULL_SPEED_STEPS
from osg_control.execution.defaults import load_defaults
from osg_control.execution.executor import Executor
from osg_control.franka.arm import FrankaConfig
from osg_control.kitchen.env import KitchenEnv
from osg_control.perception.spec import PerceptionSpec
from osg_control.robots.panda import PANDA

KITCHEN = get_domain("kitchen")
NAN = float("nan")


# ------------------------------------------------------------------ configuration
@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda: EnvConfig(perception="paper"), "EnvConfig.perception"),
        (
            lambda: KitchenEnv(config=EnvConfig(perception=PerceptionSpec("env"))),
            "EnvConfig.perception",
        ),
        (lambda: EnvConfig(max_steps=0), "EnvConfig.max_steps"),
        (lambda: EnvConfig(max_steps=2.5), "EnvConfig.max_steps"),
        (lambda: EnvConfig(max_steps=True), "EnvConfig.max_steps"),
        (lambda: EnvConfig(start_radius=-0.1), "EnvConfig.start_radius"),
        (lambda: EnvConfig(start_angle=NAN), "EnvConfig.start_angle"),
        (lambda: EnvConfig(limit_joint_speed=1), "EnvConfig.limit_joint_speed"),
        (lambda: EnvConfig(ik=None), "EnvConfig.ik"),
        (lambda: FrankaConfig(perception="env"), "FrankaConfig.perception"),
        (lambda: FrankaConfig(perception=PerceptionSpec("robot")), "FrankaConfig.perception"),
        (lambda: FrankaConfig(position_cost=-1.0), "FrankaConfig.position_cost"),
        (lambda: FrankaConfig(limit_gain=0.0), "FrankaConfig.limit_gain"),
        (lambda: FrankaConfig(limit_gain=1.5), "FrankaConfig.limit_gain"),
    ],
)
def test_configuration_fields_out_of_range_are_refused(make, field) -> None:
    with pytest.raises(EnvOptionError, match=field.replace(".", r"\.")):
        make()


def test_configurations_in_range_are_accepted() -> None:
    EnvConfig(
        perception=PerceptionSpec(tcp_noise=0.02),
        max_steps=None,
        start_radius=0.1,
        start_angle=0.2,
    )
    EnvConfig(max_steps=1, limit_joint_speed=False)
    FrankaConfig(limit_gain=1.0, posture_cost=0.0)


# ------------------------------------------------------------------ kitchen reset options
@pytest.fixture(scope="module")
def kitchen() -> KitchenEnv:
    return KitchenEnv()


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"nodes": "home"}, "unknown reset option 'nodes'; known reset options: node, "),
        ({"node": "nowhere"}, "reset option node must be one of"),
        ({"gripper": "half"}, "reset option gripper must be one of"),
        ({"holding": "kettle"}, "reset option holding must be one of"),
        ({"facts": ["door-opened"]}, "unknown fact 'door-opened'; known facts: hand-empty"),
        ({"facts": "door-open"}, "facts must be a collection"),
        ({"world": [0.3]}, "world must be a dict"),
        ({"world": {"door": 0.3}}, "unknown world reset option 'door'; known .*door_opening"),
        ({"position": "high"}, "reset option position"),
        ({"world": {"cube_pos": [5, 5, 5]}}, "out of the arm's reach"),
        ({"world": {"cube_pos": [0.5, -0.2, 0.2]}}, "does not rest on"),
        ({"world": {"cube_pos": [0.5, -0.2, -0.1]}}, "does not rest on"),
        ({"world": {"cube_pos": [0.6, 0.3, 0.0225]}}, "cuts into the cabinet's plinth"),
        ({"world": {"cube_pos": [0.35, -0.45, 0.0225]}}, "cuts into the valve"),
        ({"holding": "cube", "gripper": "open"}, "contradict.*gripper 'open' while holding"),
        ({"holding": "cube", "world": {"cube_pos": [0.4, -0.1, 0.0225]}}, "contradict"),
        ({"facts": ["door-open"], "world": {"door_opening": 0.0}}, r"contradict.*\['door-open'\]"),
        ({"facts": ["cube-in-cabinet"]}, r"contradict.*\['cube-in-cabinet'\]"),
        ({"facts": ["hand-empty"], "holding": "cube"}, r"contradict.*\['hand-empty'\]"),
    ],
)
def test_unknown_or_contradictory_reset_options_are_refused(
    kitchen: KitchenEnv, options: dict, message: str
) -> None:
    with pytest.raises(EnvOptionError, match=message):
        kitchen.reset(seed=0, options=options)


@pytest.mark.parametrize(
    ("options", "facts"),
    [
        ({"facts": ["door-open"], "world": {"door_opening": 0.35}}, {"door-open"}),
        ({"world": {"cube_pos": [0.4, -0.1, 0.0225]}}, {"cube-on-counter"}),
        (
            {
                "facts": ["cube-in-cabinet"],
                "world": {"door_opening": 0.4, "cube_pos": [0.7, 0.3, 0.1225]},
            },
            {"cube-in-cabinet", "door-open"},
        ),
        ({"facts": list(KITCHEN.start_world), "gripper": "open"}, set(KITCHEN.start_world)),
    ],
)
def test_meaningful_reset_options_are_accepted(
    kitchen: KitchenEnv, options: dict, facts: set[str]
) -> None:
    kitchen.reset(seed=0, options=options)
    assert facts <= kitchen.facts()


# ------------------------------------------------------------------ actions
REFUSED_ACTION = r"action must be a finite real array of shape \(7,\) within"
BAD_ACTIONS = [
    np.zeros(7, dtype=complex),
    {"dx": 0.01},
    np.zeros(7, dtype=bool),
    "0000000",
    [0.0, 0.0, [0.0], 0.0, 0.0, 0.0, 0.0],
    np.zeros(7, dtype=object),
]


@pytest.mark.parametrize(
    "action", BAD_ACTIONS, ids=["complex", "dict", "bool", "str", "ragged", "object"]
)
def test_actions_that_are_not_real_numbers_are_refused(kitchen: KitchenEnv, action) -> None:
    kitchen.reset(seed=0)
    ctrl, time = kitchen.data.ctrl.copy(), kitchen.data.time
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=REFUSED_ACTION):
            kitchen.step(action)
    np.testing.assert_array_equal(kitchen.data.ctrl, ctrl)
    assert kitchen.data.time == time


def test_integer_actions_are_real_numbers(kitchen: KitchenEnv) -> None:
    kitchen.reset(seed=0)
    *_, info = kitchen.step(np.array([0, 0, 0, 0, 0, 0, 1]))
    assert info["action_applied"].dtype == np.float64


# ------------------------------------------------------------------ a NaN arm joint
def test_a_nan_arm_joint_ends_the_step_as_a_named_failure(kitchen: KitchenEnv) -> None:
    kitchen.reset(seed=0)
    kitchen.data.qpos[kitchen.model.joint("panda_joint4").qposadr[0]] = NAN
    ctrl, time = kitchen.data.ctrl.copy(), kitchen.data.time
    _obs, reward, terminated, _truncated, info = kitchen.step(np.zeros(7))
    assert terminated and reward == 0.0
    assert info["failure"] == "physics diverged: non-finite qpos of joint 'panda_joint4' (nan)"
    np.testing.assert_array_equal(kitchen.data.ctrl, ctrl)  # nothing reached the actuators
    assert kitchen.data.time == time  # nothing simulated
    with pytest.raises(SimulationError, match="panda_joint4.*during joint reset"):
        kitchen.joint_reset()


@pytest.fixture(scope="module")
def executor() -> Executor:
    loaded = load_defaults(KITCHEN)
    return Executor(KITCHEN, loaded.policies, loaded.classifier, loaded.graph, max_replans=2)


@pytest.mark.parametrize("at_step", [1, 30])
def test_a_nan_arm_joint_mid_skill_ends_the_execution_as_a_failure(
    executor: Executor, at_step: int
) -> None:
    env = KitchenEnv()
    obs, _ = env.reset(seed=5, options={"node": "home"})
    steps = {"n": 0}

    def poison(e: KitchenEnv) -> None:
        steps["n"] += 1
        if steps["n"] == at_step:
            e.data.qpos[e.model.joint("panda_joint2").qposadr[0]] = NAN

    executor.on_step = poison
    try:
        result = executor.execute(["door-open", "cube-in-cabinet"], env, obs)  # never raises
    finally:
        executor.on_step = None
    assert not result.success and result.replans == 0
    assert "non-finite qpos of joint 'panda_joint2'" in (result.failure or "")


# ------------------------------------------------------------------ FrankaKitchen-v1
@pytest.fixture(scope="module")
def franka():
    pytest.importorskip("gymnasium_robotics")
    from osg_control.franka.domain import make_franka_env

    env = make_franka_env(tasks=["microwave"])
    yield env
    env.close()


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"radius": NAN}, "reset option radius"),
        ({"node": "home", "angle": -1.0}, "reset option angle"),
        ({"holding": "kettle"}, "unknown reset option 'holding'; known reset options: node"),
        ({"world": {}}, "unknown reset option 'world'"),
        ({"max_steps": -1}, "reset option max_steps"),
        ({"facts": ["no-such-fact"]}, "unknown fact 'no-such-fact'"),
        ({"facts": ["microwave-open"]}, r"contradict.*\['microwave-open'\]"),
        ({"gripper": "closed"}, "contradict.*gripper 'closed'"),
    ],
)
def test_franka_refuses_unknown_or_contradictory_reset_options(franka, options, message) -> None:
    with pytest.raises(EnvOptionError, match=message):
        franka.reset(seed=0, options=options)


def test_franka_accepts_the_start_world_and_ends_on_a_nan_arm_joint(franka) -> None:
    start = get_domain("franka-kitchen").start_world
    franka.reset(seed=0, options={"facts": list(start), "gripper": "open", "radius": 0.0})
    with pytest.raises(ValueError, match=r"shape \(7,\)"):
        franka.step(np.zeros(7, dtype=complex))
    franka.data.qpos[franka._arm_qpos[1]] = NAN
    time = franka.data.time
    _obs, _reward, terminated, _truncated, info = franka.step(np.zeros(7))
    assert terminated and "physics diverged: non-finite qpos of joint" in info["failure"]
    assert franka.data.time == time  # the env was not stepped


# ------------------------------------------------------------------ speed saturation
def test_saturation_sets_the_speed_to_the_limit_and_the_position_to_match(
    kitchen: KitchenEnv,
) -> None:
    kitchen.reset(seed=0)
    limits = np.array(PANDA.arm.velocity)
    h = kitchen.model.opt.timestep
    qvel = kitchen.data.qvel[kitchen._arm_dof]
    qvel[:] = limits * np.array([0.5, -0.9, 1.5, -2.0, 1.0, 0.0, -1.0])
    before_q, before_v = kitchen.arm_q, qvel.copy()
    saturate_joint_speeds(kitchen.data, kitchen._arm_qpos, kitchen._arm_dof, limits, h)
    after_v = kitchen.data.qvel[kitchen._arm_dof]
    np.testing.assert_array_equal(after_v, np.clip(before_v, -limits, limits))
    np.testing.assert_allclose(kitchen.arm_q, before_q - h * (before_v - after_v), atol=1e-15)
    within = np.abs(before_v) <= limits
    np.testing.assert_array_equal(kitchen.arm_q[within], before_q[within])  # untouched


def _servo_alone(env: KitchenEnv, target: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """The capped drive's substeps one by one without the saturation: the final qpos, qvel,
    and whether an arm joint ran faster than its limit on a substep."""
    limits = np.array(PANDA.arm.velocity)
    exceeded = False
    env.data.ctrl[env._arm_act] = target
    for _ in range(env.n_substeps):
        mujoco.mj_step(env.model, env.data)
        exceeded |= bool(np.any(np.abs(env.data.qvel[env._arm_dof]) > limits))
    return env.data.qpos.copy(), env.data.qvel.copy(), exceeded


def test_the_drive_acts_exactly_on_the_steps_where_a_joint_exceeds_its_limit() -> None:
    env = KitchenEnv()
    env.reset(seed=0, options={"node": "home"})
    kind = mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.empty(mujoco.mj_stateSize(env.model, kind))
    exceeded_steps = 0
    for _ in range(FULL_SPEED_STEPS):
        target = env.ik.relative_step(env.arm_q, np.array([0.02, 0, 0, 0, 0, 0]))
        mujoco.mj_getState(env.model, env.data, state, kind)
        qpos, qvel, exceeded = _servo_alone(env, target)
        mujoco.mj_setState(env.model, env.data, state, kind)
        env._simulate(target)
        same = np.array_equal(env.data.qpos, qpos) and np.array_equal(env.data.qvel, qvel)
        assert same != exceeded  # bit for bit the servo alone unless a joint exceeded
        exceeded_steps += exceeded
    assert 0 < exceeded_steps < FULL_SPEED_STEPS
    assert env.peak_joint_speed_ratio <= 1.0 + 1e-9


def test_a_control_step_in_one_call_is_the_substep_loop_bit_for_bit() -> None:
    """MuJoCo runs a control step in one call; where the speed sensors' history shows a
    joint over its limit the env reruns up to that substep and saturates: the physics and
    the reported peaks equal a substep-by-substep loop's (full-speed moves saturate)."""
    fast, loop = KitchenEnv(), KitchenEnv()
    loop.actuation.control_step._speed_watch.available = False  # the fallback: substep by substep
    fast.reset(seed=3)
    loop.reset(seed=3)
    rng = np.random.default_rng(1)
    saturated = 0
    for step in range(120):
        action = rng.uniform(-1.0, 1.0, 7) * fast.action_bounds
        if step % 40 < 20:
            action[:3] = fast.action_bounds[:3] * np.sign(action[:3])  # full speed
        fast_info, loop_info = fast.step(action)[4], loop.step(action)[4]
        np.testing.assert_array_equal(fast.data.qpos, loop.data.qpos)
        np.testing.assert_array_equal(fast.data.qvel, loop.data.qvel)
        assert fast_info["joint_speed_ratio"] == loop_info["joint_speed_ratio"]
        saturated += fast_info["joint_speed_ratio"] >= 1.0 - 1e-12
    assert saturated > 0  # the rerun path was taken


def test_full_speed_joint_motion_per_step_stays_within_the_limits() -> None:
    env = KitchenEnv()
    env.reset(seed=0, options={"node": "home"})
    limits = np.array(PANDA.arm.velocity)
    step_time = env.n_substeps * env.model.opt.timestep
    for _ in range(FULL_SPEED_STEPS):
        before = env.arm_q
        env.step(np.array([0.02, 0, 0, 0, 0, 0, 0]))
        assert np.all(np.abs(env.arm_q - before) <= limits * step_time * (1 + 1e-9))
    assert env.peak_joint_speed_ratio <= 1.0 + 1e-9
