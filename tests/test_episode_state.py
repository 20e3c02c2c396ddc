"""``EpisodeState.step_outcome``: the skill's sparse reward, termination and step budget,
kept once for ``ArmEnv`` and FrankaKitchen's adapter (each also runs it in its own tests:
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
