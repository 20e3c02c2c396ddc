"""TCP position estimation under observation noise, from the noisy readings and own actions.

The paper tests skills with Gaussian noise on the observed TCP position; a policy fed the
raw reading must decide where to grasp from a single noisy sample. ``TcpFilter`` is a
steady-state Kalman (alpha) filter over the position: it predicts the TCP's motion from the
relative actions commanded and blends in each new reading with gain ``g``::

    predicted = estimate + k_now * action_t[:3] + k_prev * action_{t-1}[:3]
    estimate  = predicted + g * (reading - predicted)

The motion model is fitted by least squares to the offline data sets, whose observations
are noise-free (``fit_motion_model``): the arm moves 0.875 of this step's command plus 0.24
of the previous one (the servos carry velocity over), 1.115 times a steady command. The
residual is about 4.5 mm per step, and with 2 cm reading noise the steady-state Kalman gain
for that ratio is 0.2, the default. For white reading noise of std sigma the estimate's
std is ``sigma * sqrt(g / (2 - g))`` (0.33 sigma at g = 0.2). The filter uses nothing but
what the policy already sees and does: no joint readings. Orientation and gripper features
pass through unchanged (they carry no noise in this project's noise model).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

DEFAULT_GAIN = 0.2
"""Blend of each new reading: the steady-state Kalman gain for 4.5 mm motion residual and
2 cm reading noise (see the module docstring and docs/results.md)."""
MOTION_MODEL = (0.875, 0.24)
"""TCP displacement per step = ``k_now * command_t + k_prev * command_{t-1}``, fitted with
``fit_motion_model`` on the fourteen default data sets (seed 0, 300 episodes each)."""


def fit_motion_model(
    observations: np.ndarray,
    actions: np.ndarray,
    next_observations: np.ndarray,
    episode_starts: np.ndarray,
) -> tuple[float, float]:
    """Least-squares ``(k_now, k_prev)`` of TCP displacement on this and the last command.

    Args:
        observations, actions, next_observations: (N, 10), (N, 7), (N, 10) noise-free
            transitions, episodes concatenated.
        episode_starts: indices of each episode's first transition (no previous command).

    Returns:
        The two coefficients, shared by the three axes.
    """
    command = np.asarray(actions, dtype=float)[:, :3]
    previous = np.vstack([np.zeros((1, 3)), command[:-1]])
    previous[np.asarray(episode_starts, dtype=int)] = 0.0
    displacement = np.asarray(next_observations)[:, :3] - np.asarray(observations)[:, :3]
    design = np.stack([command.ravel(), previous.ravel()], axis=1)
    (k_now, k_prev), *_ = np.linalg.lstsq(design, displacement.ravel(), rcond=None)
    return float(k_now), float(k_prev)


class TcpFilter:
    """Recursive TCP position estimate; ``reset`` at the start of every episode."""

    def __init__(
        self, gain: float = DEFAULT_GAIN, motion: tuple[float, float] = MOTION_MODEL
    ) -> None:
        """Args:
        gain: weight in (0, 1] of a new reading (1 = no filtering).
        motion: ``(k_now, k_prev)``, see ``MOTION_MODEL``.

        Raises:
            ValueError: a gain outside (0, 1].
        """
        if not 0.0 < gain <= 1.0:
            raise ValueError(f"filter gain must be in (0, 1], got {gain}")
        self.gain = gain
        self.motion = motion
        self._estimate: np.ndarray | None = None
        self._previous_command = np.zeros(3)

    def reset(self) -> None:
        """Forget the estimate: the next reading is taken as it is."""
        self._estimate = None
        self._previous_command = np.zeros(3)

    def update(self, obs: np.ndarray, action: np.ndarray | None) -> np.ndarray:
        """Fold in a reading taken after ``action`` (None: the robot did not move).

        Args:
            obs: the 10-D observation as read (noisy position in ``obs[:3]``).
            action: the 7-D action applied since the previous reading, or None.

        Returns:
            A copy of ``obs`` with the position replaced by the estimate.
        """
        reading = np.asarray(obs, dtype=float)
        command = np.zeros(3) if action is None else np.asarray(action, dtype=float)[:3]
        if self._estimate is None:
            self._estimate = reading[:3].copy()
        else:
            k_now, k_prev = self.motion
            predicted = self._estimate + k_now * command + k_prev * self._previous_command
            self._estimate = predicted + self.gain * (reading[:3] - predicted)
        self._previous_command = command
        filtered = reading.copy()
        filtered[:3] = self._estimate
        return filtered


class FilteredPolicy:
    """A policy that acts on filtered observations; one instance per episode."""

    def __init__(self, policy: Callable[[np.ndarray], np.ndarray], gain: float) -> None:
        self.policy = policy
        self.filter = TcpFilter(gain)
        self._last_action: np.ndarray | None = None

    def reset(self) -> None:
        """Start a new episode."""
        self.filter.reset()
        self._last_action = None

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        """The wrapped policy's action for the filtered observation."""
        action = self.policy(self.filter.update(obs, self._last_action))
        self._last_action = np.asarray(action, dtype=float)
        return action
