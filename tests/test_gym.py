"""Gymnasium registration: ``gymnasium.make("osg/Kitchen-v0")`` after ``import osg_control``,
and ``check_env`` on it (render included where an OpenGL context can be made)."""

from __future__ import annotations

import subprocess
import sys
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import osg_control  # noqa: F401  (registers the envs)
from osg_control.domain.registry import get_domain
from osg_control.environment.arm_env import EnvConfig
from osg_control.kitchen.env import KitchenEnv
from osg_control.registration import installed_envs

KITCHEN = get_domain("kitchen")

KITCHEN = "osg/Kitchen-v0"


def _can_render() -> bool:
    """Whether MuJoCo can make an offscreen OpenGL context in a fresh process."""
    code = "import mujoco; mujoco.Renderer(mujoco.MjModel.from_xml_string('<mujoco/>'))"
    probe = subprocess.run([sys.executable, "-c", code], check=False, capture_output=True)
    return probe.returncode == 0


def test_make_gives_the_kitchen_with_the_documented_step_budget() -> None:
    env = gymnasium.make(KITCHEN, skill="grab-cube")
    assert isinstance(env.unwrapped, KitchenEnv)
    assert env.spec is not None and env.spec.max_episode_steps == EnvConfig().max_steps
    assert env.unwrapped.skill is not None and env.unwrapped.skill.name == "grab-cube"
    obs, _ = env.reset(seed=0, options={"radius": 0.02, "angle": 0.05})
    assert env.observation_space.contains(obs)
    env.close()


def test_registration_is_idempotent_and_lazy() -> None:
    from osg_control.registration import register_envs

    register_envs()
    assert set(installed_envs()) <= set(gymnasium.registry)
    probe = "import osg_control, sys; print('mujoco' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", probe], check=False, capture_output=True, text=True)
    assert out.stdout.strip() == "False", "import osg_control must not load MuJoCo"


def test_observation_bound_on_force_is_the_actuators_force_range() -> None:
    env = KitchenEnv()
    gripper = env.model.actuator("gripper").id
    assert env.observation_space.high[8] == np.abs(env.model.actuator_forcerange[gripper]).max()


@pytest.mark.slow
def test_check_env_passes_without_warnings() -> None:
    render = _can_render()  # CI sets MUJOCO_GL=egl, so it checks render() too
    env = gymnasium.make(KITCHEN)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped, skip_render_check=not render)
    env.close()
