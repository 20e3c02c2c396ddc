"""``EpisodeState.step_outcome``: the skill's sparse reward, termination and step budget,
and the step loop and truth readouts around it, kept once for ``ArmEnv`` and FrankaKitchen's
adapter (each also runs it in its own tests:
``test_env.py``, ``test_franka_env.py``, ``test_franka_benchmark.py``)."""

from __future__ import annotations

import pytest

from osg_control.domain.registry import get_domain
from osg_control.environment.episode import EpisodeState


def _episode(with_skill: bool = True) -> EpisodeState:
    episode = EpisodeState()
    episode.skill = get_domain("kitchen").skill("grab-cube") if with_skill else None
    episode._succeeded = False
    episode._episode_over = False
    episode._steps = 1
    return episode


def _never() -> bool:
    raise AssertionError("success asked when it cannot matter")


def test_the_reward_is_one_on_the_step_success_first_holds() -> None:
    episode = _episode()
    assert episode.step_outcome(None, lambda: False, 10) == (0.0, False, False)
    assert not episode.episode_over
    assert episode.step_outcome(None, lambda: True, 10) == (1.0, True, False)
    assert episode.episode_over and episode._succeeded
    assert episode.step_outcome(None, _never, 10) == (0.0, False, False)  # paid once


def test_a_failure_terminates_without_asking_for_success() -> None:
    assert _episode().step_outcome("qpos[3] is nan", _never, 10) == (0.0, True, False)


@pytest.mark.parametrize(("steps", "truncated"), [(9, False), (10, True), (11, True)])
def test_the_budget_truncates_unless_the_step_terminated(steps: int, truncated: bool) -> None:
    episode = _episode()
    episode._steps = steps
    assert episode.step_outcome(None, lambda: False, 10) == (0.0, False, truncated)
    episode = _episode()
    episode._steps = steps
    assert episode.step_outcome(None, lambda: True, 10) == (1.0, True, False)


def test_an_outside_envs_own_ending_is_kept_and_no_skill_gives_no_reward() -> None:
    episode = _episode(with_skill=False)
    assert episode.step_outcome(None, _never, None, terminated=True) == (0.0, True, False)
    assert episode.step_outcome(None, _never, None, truncated=True) == (0.0, False, True)
    assert episode.step_outcome(None, _never, None) == (0.0, False, False)
    assert episode.episode_over  # stays over once a step ended it


def test_both_envs_run_the_one_step_loop_and_truth_readouts() -> None:
    """The step loop and the truth readouts exist once (``skill_step``, ``truth``): neither
    ``ArmEnv`` (through the kitchen) nor FrankaKitchen's adapter has its own; each brings
    only its plant (``Actuation``) and hooks."""
    pytest.importorskip("gymnasium_robotics")
    from osg_control.environment.skill_step import SkillStepper
    from osg_control.environment.stepping import MujocoActuation
    from osg_control.environment.truth import TruthReadouts
    from osg_control.franka.actuation import KitchenStepActuation
    from osg_control.franka.domain import make_franka_env
    from osg_control.franka.env import FrankaKitchenAdapter
    from osg_control.kitchen.env import KitchenEnv

    for env in (KitchenEnv, FrankaKitchenAdapter):
        assert env.step is SkillStepper.step and env.advance is SkillStepper.advance
        for name in ("skill_success", "_truth_success", "tcp_pose", "facts", "node_position"):
            assert getattr(env, name) is getattr(TruthReadouts, name), (env.__name__, name)
    kitchen, adapter = KitchenEnv(), make_franka_env(tasks=["microwave"])
    assert isinstance(kitchen.actuation, MujocoActuation)
    assert isinstance(adapter.actuation, KitchenStepActuation)
    adapter.close()
