"""The TCP filter: noise reduction, tracking of commanded motion, and its wiring into eval."""

from __future__ import annotations

import numpy as np
import pytest

from osg_control.control.estimator import (
    MOTION_MODEL,
    FilteredPolicy,
    TcpFilter,
    TcpTracker,
    fit_motion_model,
)
from osg_control.data.collect import run_scripted_episode
from osg_control.domain.registry import get_domain

KITCHEN = get_domain("kitchen")

SIGMA = 0.02


def _readings(true_path: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """10-D observations along a TCP path with Gaussian position noise, and the true path."""
    obs = np.zeros((len(true_path), 10))
    obs[:, :3] = true_path + rng.normal(0.0, SIGMA, true_path.shape)
    obs[:, 3:7] = (0.0, 1.0, 0.0, 0.0)
    obs[:, 7] = 1.0
    return obs, true_path


@pytest.mark.parametrize("gain", [0.1, 0.2, 0.5])
def test_error_std_matches_the_steady_state_formula(gain: float) -> None:
    rng = np.random.default_rng(0)
    obs, truth = _readings(np.tile([0.4, 0.1, 0.3], (20000, 1)), rng)
    tcp_filter = TcpFilter(gain)
    estimates = np.array([tcp_filter.update(o, np.zeros(7))[:3] for o in obs])
    error = (estimates - truth)[200:]
    expected = SIGMA * np.sqrt(gain / (2.0 - gain))
    assert np.allclose(error.std(axis=0), expected, rtol=0.05)
    assert np.all(np.abs(error.mean(axis=0)) < 0.1 * expected)


def test_follows_commanded_motion_without_lag() -> None:
    rng = np.random.default_rng(1)
    command = np.array([0.01, -0.005, 0.002])
    step = sum(MOTION_MODEL) * command  # how far a steady command moves the arm
    truth = np.array([0.3, 0.0, 0.4]) + np.arange(3000)[:, None] * step
    obs, _ = _readings(truth, rng)
    tcp_filter = TcpFilter(0.2)
    action = np.concatenate([command, np.zeros(4)])
    estimates = np.array(
        [tcp_filter.update(o, None if i == 0 else action)[:3] for i, o in enumerate(obs)]
    )
    error = (estimates - truth)[100:]
    assert np.all(np.abs(error.mean(axis=0)) < 0.002)  # no drift behind the moving TCP
    assert np.all(error.std(axis=0) < 0.5 * SIGMA)


def test_only_the_position_changes_and_reset_forgets() -> None:
    tcp_filter = TcpFilter(0.5)
    first = np.arange(10.0)
    np.testing.assert_array_equal(tcp_filter.update(first, None), first)
    second = first + 1.0
    filtered = tcp_filter.update(second, None)
    np.testing.assert_allclose(filtered[:3], first[:3] + 0.5)
    np.testing.assert_array_equal(filtered[3:], second[3:])
    tcp_filter.reset()
    np.testing.assert_array_equal(tcp_filter.update(second, None), second)


@pytest.mark.parametrize("gain", [0.0, -0.1, 1.5])
def test_gain_outside_range_is_refused(gain: float) -> None:
    with pytest.raises(ValueError, match="gain"):
        TcpFilter(gain)


def test_filtered_policy_feeds_its_own_actions_back() -> None:
    seen: list[np.ndarray] = []

    def policy(obs: np.ndarray) -> np.ndarray:
        seen.append(obs.copy())
        return np.array([0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])

    wrapped = FilteredPolicy(policy, gain=0.5)
    obs = np.zeros(10)
    wrapped(obs)
    wrapped(obs)  # predicted k_now * 0.01, reading 0 -> half of it
    assert seen[1][0] == pytest.approx(0.5 * MOTION_MODEL[0] * 0.01)
    wrapped.reset()
    wrapped(obs)
    assert seen[2][0] == 0.0


def test_tracker_folds_each_reading_once_with_the_actions_before_it() -> None:
    tracker = TcpTracker(gain=0.5)
    first = np.zeros(10)
    np.testing.assert_array_equal(tracker.read(first), first)
    tracker.acted(np.array([0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
    second = np.zeros(10)  # the arm did not move as commanded: estimate halfway
    expected = 0.5 * MOTION_MODEL[0] * 0.01
    assert tracker.read(second)[0] == pytest.approx(expected)
    # The same reading again (e.g. the executor plans from it, then the next skill starts
    # from it): not folded twice.
    assert tracker.read(second)[0] == pytest.approx(expected)
    # A new reading with no action since: a resting arm (the previous command's lag term
    # still applies).
    third = np.zeros(10)
    third[0] = 0.004
    rest = expected + MOTION_MODEL[1] * 0.01
    assert tracker.read(third)[0] == pytest.approx(rest + 0.5 * (0.004 - rest))
    # After settle (the joint reset stopped the arm) no command is carried into the
    # next reading's prediction.
    estimate = tracker.read(third)[0]
    tracker.acted(np.array([0.02, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
    tracker.settle()
    fourth = np.zeros(10)
    assert tracker.read(fourth)[0] == pytest.approx(0.5 * estimate)


@pytest.mark.slow
def test_motion_model_matches_the_simulated_arm() -> None:
    # Refit on fresh scripted episodes of every skill (as MOTION_MODEL was fitted, on all
    # the data sets): if the controller's tracking changes, MOTION_MODEL must be refitted.
    # One skill alone is not enough: move-cabinet-to-home's episodes give k_now ~0.98.
    episodes = [
        run_scripted_episode(KITCHEN, skill, 3, i) for skill in KITCHEN.skills for i in range(3)
    ]
    lengths = np.array([len(e.actions) for e in episodes])
    k_now, k_prev = fit_motion_model(
        np.concatenate([e.observations for e in episodes]),
        np.concatenate([e.actions for e in episodes]),
        np.concatenate([e.next_observations for e in episodes]),
        np.concatenate([[0], np.cumsum(lengths)[:-1]]),
    )
    assert k_now == pytest.approx(MOTION_MODEL[0], abs=0.1)
    assert k_prev == pytest.approx(MOTION_MODEL[1], abs=0.1)
    assert k_now + k_prev == pytest.approx(sum(MOTION_MODEL), abs=0.06)
