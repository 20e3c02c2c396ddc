"""Perception: the executor decides from percepts only; named perceptions and their noise."""

from __future__ import annotations

import json
import re
from typing import Any

import numpy as np
import pytest

from osg_control.cli import main
from osg_control.domain.registry import get_domain
from osg_control.environment.arm_env import EnvConfig
from osg_control.errors import UsageError
from osg_control.execution.defaults import load_defaults
from osg_control.execution.executor import Executor, task_env_config
from osg_control.kitchen.env import KitchenEnv
from osg_control.perception.spec import (
    ENCODER_NOISE,
    OBJECT_NOISE,
    PerceptionSpec,
    check_supported,
    perception_spec,
)

KITCHEN = get_domain("kitchen")


class TruthAccessed(AssertionError):
    """Something read the simulator's truth outside scoring."""


class GuardedKitchenEnv(KitchenEnv):
    """The kitchen whose truth accessors raise unless ``scoring`` is set, and whose step
    info carries no truth: only the percepts are left to decide from."""

    scoring = False

    def _guard(self, name: str) -> None:
        if not self.scoring:
            raise TruthAccessed(f"env.{name} read outside scoring")

    def facts(self) -> frozenset[str]:
        self._guard("facts")
        return super().facts()

    def world_state(self) -> np.ndarray:
        self._guard("world_state")
        return super().world_state()

    def world(self) -> Any:
        self._guard("world")
        return super().world()

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        self._guard("tcp_pose")
        return super().tcp_pose()

    @property
    def arm_q(self) -> np.ndarray:
        self._guard("arm_q")
        return KitchenEnv.arm_q.fget(self)  # type: ignore[attr-defined]

    def _info(self, world: Any = None, facts: Any = None) -> dict[str, Any]:
        """The step's info is the env's own scoring (``step`` strips its truth)."""
        self.scoring, before = True, self.scoring
        try:
            return super()._info(world, facts)
        finally:
            self.scoring = before

    def skill_success(self, skill: Any = None, world: Any = None) -> bool:
        self._guard("skill_success")
        return super().skill_success(skill, world)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = super().step(action)
        for truth in ("world", "world_facts", "success", "arm_q"):
            info.pop(truth)
        return obs, reward, terminated, truncated, info


@pytest.fixture(scope="module")
def executor() -> Executor:
    defaults = load_defaults(KITCHEN)
    return Executor(KITCHEN, defaults.policies, defaults.classifier, defaults.graph)


@pytest.mark.parametrize(
    "perception", [perception_spec("paper", 0.02), perception_spec("robot")], ids=["paper", "robot"]
)
def test_the_executor_runs_a_task_on_percepts_alone(executor: Executor, perception) -> None:
    env = GuardedKitchenEnv(config=task_env_config(perception))
    obs, _ = env.reset(seed=3, options={"node": "home"})
    executor.filter_gain = 0.2 if perception.tcp_noise else None
    result = executor.execute(["cube-lifted"], env, obs)
    assert result.success, result.failure
    assert result.plan[-2:] == ["grab-cube cube-1", "pick-up-cube cube-1"]
    assert any(outcome.reset_steps for outcome in result.outcomes)  # joint resets ran, guarded
    env.scoring = True
    assert "cube-lifted" in env.facts()  # scored on the simulator's truth


def test_the_guard_catches_a_truth_read() -> None:
    env = GuardedKitchenEnv()
    env.reset(seed=0)
    with pytest.raises(TruthAccessed, match="env.facts"):
        env.facts()
    with pytest.raises(TruthAccessed, match="env.arm_q"):
        env.arm_q  # noqa: B018
    _obs, *_, info = env.step(np.zeros(7))
    assert "world" not in info and "percept" in info


def test_the_robot_percept_takes_the_tcp_from_noisy_encoders() -> None:
    env = KitchenEnv(config=EnvConfig(perception=perception_spec("robot")))
    env.reset(seed=0)
    errors, joint_errors, cube_errors = [], [], []
    for _ in range(30):
        env.step(np.zeros(7))
        percept = env.percept()
        errors.append(np.linalg.norm(percept.position - env.tcp_pose()[0]))
        joint_errors.append(percept.joints - env.arm_q)
        cube_errors.append(percept.world[2:5] - env.world_state()[2:5])
    assert 0 < np.mean(errors) < 0.005  # millimetres: 7 encoders of 0.5 mrad
    assert np.std(joint_errors) == pytest.approx(ENCODER_NOISE, rel=0.3)
    assert np.std(cube_errors) == pytest.approx(OBJECT_NOISE, rel=0.3)
    assert env.percept().facts == env.facts()  # the cube on the counter, seen through noise


def test_the_paper_percept_has_exact_objects_and_a_noisy_tcp() -> None:
    env = KitchenEnv(config=EnvConfig(perception=perception_spec("paper", 0.02)))
    env.reset(seed=0)
    percept = env.percept()
    assert np.linalg.norm(percept.position - env.tcp_pose()[0]) > 0
    np.testing.assert_array_equal(percept.joints, env.arm_q)
    np.testing.assert_array_equal(percept.world[:9], env.world_state()[:9])


def test_a_grasp_is_detected_from_the_finger_width_not_from_contacts() -> None:
    env = KitchenEnv(config=EnvConfig(perception=perception_spec("robot")))
    env.reset(seed=0, options={"node": "cube-lifted", "holding": "cube"})
    assert "holding-cube" in env.percept().facts
    env.reset(seed=0, options={"node": "cube-lifted", "gripper": "closed"})  # shut on nothing
    assert "holding-cube" not in env.percept().facts


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ("lidar",),
            "unknown perception 'lidar'; known perceptions: paper, robot, camera, env, sim",
        ),
        (("paper", -0.01), "--noise must be finite and in [0, 1]"),
        (("paper", float("nan")), "--noise must be finite and in [0, 1]"),
        (("robot", 0.0, float("inf")), "--object-noise must be finite and in [0, 1]"),
        (("paper", 1e300), "--noise must be finite and in [0, 1]"),
        (("robot", 0.0, 1.5), "--object-noise must be finite and in [0, 1]"),
        (("paper", True), "--noise must be finite and in [0, 1]"),
        (("robot", 0.02), "--noise is the paper protocol's TCP noise"),
        (("paper", 0.0, 0.01), "--object-noise applies to the robot perception"),
    ],
)
def test_bad_perceptions_are_refused(args: tuple, message: str) -> None:
    with pytest.raises(UsageError, match=re.escape(message)):
        perception_spec(*args)


def test_a_spec_refuses_a_negative_noise_and_a_domain_refuses_an_unknown_perception() -> None:
    with pytest.raises(UsageError, match="tcp_noise must be finite"):
        PerceptionSpec(tcp_noise=-1.0)
    with pytest.raises(UsageError, match="does not support perception 'env'"):
        check_supported(PerceptionSpec("env"), KITCHEN.perceptions, "kitchen")


@pytest.mark.parametrize(
    "argv",
    [
        ["evaluate", "tasks", "--perception", "lidar"],
        ["evaluate", "tasks", "--perception", "env"],
        ["evaluate", "tasks", "--perception", "robot", "--object-noise", "-1"],
        ["run", "--goal", "cube-lifted", "--perception", "paper", "--noise", "nan"],
        ["classifier", "reach", "--perception", "robot", "--noise", "0.02"],
        ["eval-skills", "--perception", "bogus"],
    ],
)
def test_the_cli_refuses_a_bad_perception_with_exit_2(argv: list[str], capsys) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "perception" in err or "noise" in err, err


def test_run_json_carries_the_perception(capsys) -> None:
    argv = ["run", "--goal", "cube-lifted", "--start", "home", "--perception", "robot", "--json"]
    main(argv)
    payload = json.loads(capsys.readouterr().out)
    assert payload["perception"]["name"] == "robot"
    assert payload["perception"]["object_noise"] == OBJECT_NOISE
    assert payload["episodes"][0]["scored_success"] is True


@pytest.mark.parametrize(
    "options",
    [{}, {"node": "cube-lifted", "holding": "cube"}, {"facts": ["door-open"]}],
    ids=["counter", "lifted", "door-open"],
)
def test_robot_percept_facts_do_not_flicker_at_rest(options: dict) -> None:
    """The fact thresholds leave room for the pose estimator's 1 cm noise: 300 readings of a
    resting scene all give the true facts."""
    env = KitchenEnv(config=EnvConfig(perception=perception_spec("robot"), max_steps=None))
    env.reset(seed=0, options=options)
    wrong = 0
    for _ in range(300):
        env.step(np.zeros(7))
        wrong += env.percept().facts != env.facts()
    assert wrong == 0
