"""A physics divergence ends an execution as a failure that names it, on every path, and a
start that means nothing is refused. Divergences are injected into the real simulator
(a huge joint velocity, which MuJoCo reports as BADQVEL and answers with a reset)."""

from __future__ import annotations

import numpy as np
import pytest

from osg_control.domain.registry import get_domain
from osg_control.errors import EnvOptionError, SimulationError
from osg_control.execution.defaults import load_defaults
from osg_control.execution.executor import Executor
from osg_control.kitchen.env import KitchenEnv

KITCHEN = get_domain("kitchen")

GOAL = ["door-open", "cube-in-cabinet"]


@pytest.fixture(scope="module")
def executor() -> Executor:
    _loaded = load_defaults(KITCHEN)
    policies, classifier = _loaded.policies, _loaded.classifier
    return Executor(KITCHEN, policies, classifier, _loaded.graph, max_replans=2)


def _poison(env: KitchenEnv) -> None:
    env.data.qvel[:] = 1e30


def _start(seed: int = 5) -> tuple[KitchenEnv, np.ndarray]:
    env = KitchenEnv()
    obs, _ = env.reset(seed=seed, options={"node": "home"})
    return env, obs


def test_divergence_mid_skill_fails_without_replanning(executor: Executor) -> None:
    env, obs = _start()
    steps = {"n": 0}

    def inject(e: KitchenEnv) -> None:
        steps["n"] += 1
        if steps["n"] == 30:  # during the third skill, after the handle was grabbed
            _poison(e)

    executor.on_step = inject
    try:
        result = executor.execute(GOAL, env, obs)
    finally:
        executor.on_step = None
    assert not result.success
    assert "physics diverged" in (result.failure or "")
    assert result.replans == 0  # never replans from the reset world
    assert "physics diverged" in (result.outcomes[-1].failure or "")


def test_divergence_during_joint_reset_ends_as_failure(executor: Executor) -> None:
    env, obs = _start()
    original = env.joint_reset

    def poisoned_reset(*args, **kwargs) -> int:
        _poison(env)
        return original(*args, **kwargs)

    env.joint_reset = poisoned_reset  # type: ignore[method-assign]
    result = executor.execute(GOAL, env, obs)  # must not raise
    assert not result.success
    assert "joint reset" in (result.failure or "") and "physics diverged" in result.failure
    assert result.replans == 0


@pytest.mark.parametrize(
    "options",
    [
        {"world": {"door_opening": float("nan")}},
        {"world": {"door_opening": 0.9}},
        {"world": {"door_opening": -0.1}},
        {"world": {"cube_pos": [0.5, float("inf"), 0.1]}},
        {"position": [0.4, float("nan"), 0.3]},
        {"radius": -1.0},
        {"angle": float("nan")},
    ],
)
def test_meaningless_start_options_are_refused(options: dict) -> None:
    env = KitchenEnv()
    with pytest.raises(EnvOptionError, match="reset option"):
        env.reset(seed=0, options=options)


def test_divergence_while_placing_the_start_is_detected() -> None:
    env = KitchenEnv()
    original = env._settle

    def poisoned_settle(seconds: float) -> None:
        _poison(env)
        original(seconds)

    env._settle = poisoned_settle  # type: ignore[method-assign]
    with pytest.raises(SimulationError, match="physics diverged.*placing the start"):
        env.reset(seed=0)
