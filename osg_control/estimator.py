"""TCP position estimation under observation noise, from the noisy readings and own actions.

The paper tests skills with Gaussian noise on the observed TCP position; a policy fed the
raw reading must decide where to grasp from a single noisy sample. ``TcpFilter`` is a
steady-state Kalman (alpha) filter over the position: it predicts the TCP's motion from the
relative action just commanded (the controller tracks it to within a few percent per
50 ms step) and blends in each new reading with gain ``g``::

    predicted = estimate + action[:3]
    estimate  = predicted + g * (reading - predicted)

For white reading noise of std sigma the estimate's std is ``sigma * sqrt(g / (2 - g))``
(0.33 sigma at g = 0.2). It uses nothing but what the policy already sees and does; no
joint readings. Orientation and gripper features pass through unchanged (they carry no
noise in this project's noise model).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

DEFAULT_GAIN = 0.2
"""Blend of each new reading; chosen by ``osg eval-skills --filter`` sweeps (docs/results.md)."""


class TcpFilter:
    """Recursive TCP position estimate; ``reset`` at the start of every episode."""

    def __init__(self, gain: float = DEFAULT_GAIN) -> None:
        """Args:
        gain: weight in (0, 1] of a new reading (1 = no filtering).

        Raises:
            ValueError: a gain outside (0, 1].
        """
        if not 0.0 < gain <= 1.0:
            raise ValueError(f"filter gain must be in (0, 1], got {gain}")
        self.gain = gain
        self._estimate: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the estimate: the next reading is taken as it is."""
        self._estimate = None

    def update(self, obs: np.ndarray, action: np.ndarray | None) -> np.ndarray:
        """Fold in a reading taken after ``action`` (None: the robot did not move).

        Args:
            obs: the 10-D observation as read (noisy position in ``obs[:3]``).
            action: the 7-D action applied since the previous reading, or None.

        Returns:
            A copy of ``obs`` with the position replaced by the estimate.
        """
        reading = np.asarray(obs, dtype=float)
        if self._estimate is None:
            self._estimate = reading[:3].copy()
        else:
            predicted = self._estimate + (0.0 if action is None else np.asarray(action)[:3])
            self._estimate = predicted + self.gain * (reading[:3] - predicted)
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
