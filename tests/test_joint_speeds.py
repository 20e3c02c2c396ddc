"""Simulated joint speeds stay near the URDF velocity limits on every physics substep: the
servo target is spread over the substeps (``control.servo``) instead of jumping, with
``EnvConfig(limit_joint_speed=True)``. Without it the shipped grab-cube and release-handle
policies peak at 2.6-2.7x the limits (``test_without_the_ramp_speeds_exceed_the_limits``)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from osg_control.control.ik import urdf_velocity_limits
from osg_control.control.servo import substep_targets
from osg_control.domain.registry import get_domain
from osg_control.execution.defaults import load_defaults
from osg_control.kitchen.env import EnvConfig, KitchenEnv

KITCHEN = get_domain("kitchen")

TOLERANCE = 1.15
"""Allowed peak |qvel| / limit: the position servos are slightly under-damped, so a ramp at
the limit overshoots it by up to about 12 % (measured with tools/joint_speeds.py)."""


def test_substep_targets_ramp_within_the_increment_then_hold() -> None:
    limit = np.array([1.0, 1.0])
    targets = substep_targets(np.zeros(2), np.array([1.0, -2.0]), 4, limit)
    np.testing.assert_allclose(targets, [[0.5, -1.0], [1.0, -2.0], [1.0, -2.0], [1.0, -2.0]])
    full = substep_targets(np.zeros(2), np.array([4.0, 0.0]), 4, limit)
    np.testing.assert_allclose(full[:, 0], [1.0, 2.0, 3.0, 4.0])
    assert np.all(np.abs(np.diff(full, axis=0, prepend=0.0)) <= limit + 1e-12)


@pytest.fixture(scope="module")
def policies() -> dict:
    return load_defaults(KITCHEN).policies


@pytest.mark.parametrize(
    "skill", ["grab-cube", "pick-up-cube", "release-handle", "move-cube-to-home"]
)
def test_shipped_skills_respect_velocity_limits_on_every_substep(skill, policies, monkeypatch):
    assert _peak_ratio(skill, policies, monkeypatch, limit=True) <= TOLERANCE


def test_without_the_ramp_speeds_exceed_the_limits(policies, monkeypatch):
    assert _peak_ratio("grab-cube", policies, monkeypatch, limit=False) > 2.0


def _peak_ratio(skill: str, policies: dict, monkeypatch, limit: bool) -> float:
    """Peak |qvel| / limit over every substep of two episodes and their joint resets."""
    env = KitchenEnv(skill=skill, config=EnvConfig(limit_joint_speed=limit))
    limits = urdf_velocity_limits()
    ratios: list[float] = []
    recording = False
    step = mujoco.mj_step

    def recording_step(model: mujoco.MjModel, data: mujoco.MjData) -> None:
        step(model, data)
        if recording:
            ratios.append(float(np.max(np.abs(data.qvel[env._arm_dof]) / limits)))

    monkeypatch.setattr(mujoco, "mj_step", recording_step)
    for episode in range(2):
        recording = False
        obs, _ = env.reset(seed=episode, options={"radius": 0.05, "angle": 0.1})
        recording = True
        for _ in range(env.skill.max_steps):
            obs, _r, terminated, truncated, _info = env.step(policies[skill](obs))
            if terminated or truncated:
                break
        env.joint_reset()
    assert len(ratios) >= 25 * 10  # every substep of at least ten control steps
    return max(ratios)
