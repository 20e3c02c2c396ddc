"""Reliability, round 4: the Python API is as strict as the CLI. Each call that means
nothing is a named ``EnvOptionError``/``ValueError`` (never a bare ``AttributeError``,
``IndexError`` or ``TypeError``, never a silent other meaning), and a refused call leaves the
env usable."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium
import numpy as np
import pytest

import osg_control  # noqa: F401  (registers the Gymnasium ids)
from osg_control.domain.registry import get_domain
from osg_control.errors import EnvOptionError
from osg_control.execution.executor import load_executor

KITCHEN = get_domain("kitchen")
FRANKA = get_domain("franka-kitchen")


@pytest.fixture(scope="module")
def kitchen_env() -> Any:
    return KITCHEN.make_env()


@pytest.fixture(scope="module")
def franka_env() -> Any:
    return FRANKA.make_env()


BAD_RESETS: list[tuple[str, Any, str]] = [
    ("options a string", "node", "reset options must be a dict"),
    ("options a number", 5, "reset options must be a dict"),
    ("empty node", {"node": ""}, "reset option node must be one of"),
    ("facts a dict", {"facts": {"door-open": False}}, "a fact mapped to False"),
    ("facts nested", {"facts": [["door-open"]]}, "must hold fact names (strings)"),
    ("facts a string", {"facts": "door-open"}, "must be a collection of facts"),
    ("radius True", {"radius": True}, "reset option radius must be finite numbers"),
    ("radius a string", {"radius": "0.1"}, "reset option radius must be finite numbers"),
    ("position strings", {"position": ["0", "0", "1"]}, "reset option position must be"),
]


def test_facts_as_a_dict_never_start_the_door_open(kitchen_env: Any) -> None:
    """The wrong result of round 4: ``{"door-open": False}`` started with the door open."""
    with pytest.raises(EnvOptionError):
        kitchen_env.reset(seed=0, options={"facts": {"door-open": False}})
    kitchen_env.reset(seed=0, options={"facts": ["door-open"]})
    assert "door-open" in kitchen_env.facts()
    kitchen_env.reset(seed=0, options={"facts": []})
    assert "door-open" not in kitchen_env.facts()


FRANKA_RESETS: list[tuple[str, Any, str]] = [
    ("options a string", "node", "reset options must be a dict"),
    ("empty node", {"node": ""}, "reset option node must be one of"),
    ("facts a dict", {"facts": {"kettle-moved": False}}, "a fact mapped to False"),
    ("radius True", {"radius": True}, "reset option radius must be finite numbers"),
    ("out of reach", {"position": [50.0, 50.0, 50.0]}, "out of the arm's reach (1.089 m)"),
]


RESETS = [("kitchen_env", *case) for case in BAD_RESETS] + [
    ("franka_env", *case) for case in FRANKA_RESETS
]


@pytest.mark.parametrize(
    ("env_name", "case", "options", "fragment"), RESETS, ids=[r[1] for r in RESETS]
)
def test_meaningless_resets_are_named_and_leave_the_env_usable(
    env_name: str, case: str, options: Any, fragment: str, request: pytest.FixtureRequest
) -> None:
    env = request.getfixturevalue(env_name)
    with pytest.raises(EnvOptionError) as raised:
        env.reset(seed=0, options=options)
    assert fragment in str(raised.value), case
    if env_name == "kitchen_env":  # the kitchen steps in microseconds: check it still runs
        obs, _ = env.reset(seed=0)
        assert np.all(np.isfinite(env.step(np.zeros(7))[0])) and obs.shape == (10,)


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"skill": 5}, "skill must be a skill name or a SkillSpec, got 5"),
        ({"config": "x"}, "config must be a EnvConfig, got 'x'"),
    ],
)
def test_gymnasium_make_names_a_wrong_argument(kwargs: dict[str, Any], fragment: str) -> None:
    with pytest.raises(EnvOptionError, match=fragment):
        gymnasium.make("osg/Kitchen-v0", **kwargs)


def test_a_refused_first_reset_leaves_the_made_env_usable() -> None:
    env = gymnasium.make("osg/Kitchen-v0")
    with pytest.raises(EnvOptionError):
        env.reset(seed=0, options={"node": "nowhere"})
    env.reset(seed=0)
    obs, reward, *_ = env.step(np.zeros(7))
    assert obs.shape == (10,) and reward == 0.0
    env.close()


EXECUTE: list[tuple[str, Callable[[Any, Any, Any], Any], str]] = [
    ("obs of 3", lambda ex, env, obs: ex.execute(["door-open"], env, np.zeros(3)), "shape (10,)"),
    ("obs NaN", lambda ex, env, obs: ex.execute(["door-open"], env, obs * np.nan), "non-finite"),
    ("goal a number", lambda ex, env, obs: ex.execute(5, env, obs), "collection"),
    ("goal atom", lambda ex, env, obs: ex.execute("(on a b)", env, obs), "unknown predicate 'on'"),
    (
        "goal object",
        lambda ex, env, obs: ex.execute("(lifted cube-7)", env, obs),
        "unknown object 'cube-7'",
    ),
    ("goal arity", lambda ex, env, obs: ex.execute("(lifted)", env, obs), "takes 1 argument"),
    ("unknown node", lambda ex, env, obs: ex.execute("(at nowhere)", env, obs), "unknown node"),
    ("goal nested", lambda ex, env, obs: ex.execute([["door-open"]], env, obs), "fact names"),
]


@pytest.mark.parametrize(("case", "call", "fragment"), EXECUTE, ids=[e[0] for e in EXECUTE])
def test_execute_refuses_what_is_not_a_goal_or_an_observation(
    case: str, call: Callable[[Any, Any, Any], Any], fragment: str, kitchen_env: Any
) -> None:
    executor = load_executor(KITCHEN)
    obs, _ = kitchen_env.reset(seed=0)
    with pytest.raises(ValueError) as raised:
        call(executor, kitchen_env, obs)
    assert fragment in str(raised.value), case


def test_an_at_node_goal_is_reached_and_scored(kitchen_env: Any) -> None:
    """``(at NODE)`` was driven to and then reported failed (``(at`` is no world fact)."""
    executor = load_executor(KITCHEN)
    obs, _ = kitchen_env.reset(seed=0)
    result = executor.execute("(at above-valve)", kitchen_env, obs)
    assert result.success and result.plan == ["move-home-to-valve valve-1"]
    assert result.goal == ["(at above-valve)"]
    obs, _ = kitchen_env.reset(seed=0)
    both = executor.execute(["door-open", "(at home)"], kitchen_env, obs)
    assert both.success and "door-open" in kitchen_env.facts()
