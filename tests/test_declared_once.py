"""A domain is declared once: its env is checked against it when built (the contract, the
action bounds, the perceptions), and what the core derives from it (training's scale, the
scripted policy's bounds, the exports' spaces) is the domain's own."""

from __future__ import annotations

import dataclasses
import functools
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from datagen import chained_dataset

from osg_control.cli import main
from osg_control.data.minari_export import export_minari
from osg_control.domain import registry
from osg_control.domain.contract import SkillEnv, missing_members
from osg_control.domain.registry import get_domain, register_domain
from osg_control.domain.spaces import CheckedEnvFactory, EnvMismatchError, observation_bounds
from osg_control.errors import DomainError
from osg_control.robots.registry import get_robot

KITCHEN = get_domain("kitchen")
WIDER = (0.04, 0.04, 0.04, 0.2, 0.2, 0.2, 1.0)


def test_the_kitchen_env_implements_the_contract_with_the_domains_spaces() -> None:
    env = KITCHEN.make_env()
    assert isinstance(env, SkillEnv) and missing_members(env) == []
    np.testing.assert_array_equal(env.action_space.high, KITCHEN.action_bounds)
    np.testing.assert_array_equal(env.action_bounds, KITCHEN.action_bounds)
    low, high = KITCHEN.observation_bounds()
    np.testing.assert_array_equal(env.observation_space.low, low)
    np.testing.assert_array_equal(env.observation_space.high, high)
    assert set(KITCHEN.perceptions) <= set(env.perceptions)


def test_an_env_with_other_bounds_than_its_domain_is_refused_when_built() -> None:
    domain = dataclasses.replace(KITCHEN, name="wide", action_bounds=WIDER)
    with pytest.raises(EnvMismatchError, match=r"domain 'wide'.*action_bounds") as info:
        domain.make_env()
    assert isinstance(info.value, DomainError)


def test_an_env_without_a_perception_of_its_domain_is_refused_when_built() -> None:
    domain = dataclasses.replace(KITCHEN, name="seeing", perceptions=("paper", "env"))
    with pytest.raises(EnvMismatchError, match=r"does not simulate the domain's perceptions"):
        domain.make_env()


class _Partial:
    """An env that has only some of the contract (no ``tcp_pose``, ``placement_world``...)."""

    def reset(self, **_: Any) -> None: ...

    def step(self, action: np.ndarray) -> None: ...


def test_an_env_lacking_contract_members_is_refused_naming_them() -> None:
    domain = dataclasses.replace(KITCHEN, name="partial", make_env=lambda **_: _Partial())
    with pytest.raises(EnvMismatchError, match=r"lacks the SkillEnv members \[.*'tcp_pose'"):
        domain.make_env()


def test_with_robot_keeps_the_check() -> None:
    """``with_robot`` re-wraps the domain's own factory once (its envs are still checked)."""
    other = KITCHEN.with_robot("ur5")
    assert isinstance(other.make_env, CheckedEnvFactory)
    assert isinstance(other.make_env.factory, functools.partial)
    assert other.make_env.factory.func is KITCHEN.make_env.factory
    assert list(other.make_env.factory.keywords) == ["robot"]
    assert other.make_env.factory.keywords["robot"].name == "ur5"  # at its kitchen mount


def test_observation_bounds_are_the_robots() -> None:
    robot = get_robot(KITCHEN.robot or "")
    low, high = observation_bounds(robot)
    assert high[8] == robot.gripper.force and low[8] == 0.0
    assert high[9] == pytest.approx(robot.gripper.max_opening + 0.02)
    np.testing.assert_array_equal(high, KITCHEN.observation_bounds()[1])


def test_minari_export_writes_the_domains_own_spaces(tmp_path: Path) -> None:
    """A domain with 4 cm bounds exports 4 cm bounds (before, every domain got 2 cm)."""
    source = chained_dataset(tmp_path / "toy.h5")
    wide = dataclasses.replace(KITCHEN, name="wide", action_bounds=WIDER)
    for domain, dataset_id in ((KITCHEN, "osg/narrow-v0"), (wide, "osg/wide-v0")):
        target = export_minari(source, dataset_id, domain, tmp_path / "root")
        metadata = json.loads((target / "data" / "metadata.json").read_text())
        action = json.loads(metadata["action_space"])
        observation = json.loads(metadata["observation_space"])
        np.testing.assert_allclose(action["high"], domain.action_bounds, rtol=1e-6)
        np.testing.assert_allclose(observation["high"], domain.observation_bounds()[1], rtol=1e-6)


def test_randomize_objects_on_a_domain_without_objects_is_a_usage_error(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Exit 2 naming the reason, before any model or env is loaded."""
    bare = dataclasses.replace(
        KITCHEN,
        name="bare",
        objects=(),
        nodes={n: dataclasses.replace(v, anchor=None) for n, v in KITCHEN.nodes.items()},
        instances=tuple(dataclasses.replace(i, frame=None) for i in KITCHEN.instances),
    )
    monkeypatch.setattr(registry, "_FACTORIES", dict(registry._FACTORIES))  # kept to this test
    register_domain("bare", lambda: bare)
    for argv in (
        ["--domain", "bare", "run", "--goal", "door-open", "--randomize-objects"],
        ["--domain", "bare", "evaluate", "tasks", "--randomize-objects"],
        ["--domain", "bare", "eval-skills", "--randomize-objects"],
    ):
        assert main(argv) == 2, argv
        assert "domain 'bare' has no object with a placement region" in capsys.readouterr().err
