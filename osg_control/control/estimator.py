"""TCP position estimation under observation noise, from the noisy readings and own actions.

The paper tests skills with Gaussian noise on the observed TCP position; a policy fed the
raw reading must decide where to grasp from a single noisy sample. ``TcpFilter`` is a
steady-state Kalman (alpha) filter over the position: it predicts the TCP's motion from the
relative actions commanded and blends in each new reading with gain ``g``::

    predicted = estimate + k_now * action_t[:3] + k_prev * action_{t-1}[:3]
    estimate  = predicted + g * (reading - predicted)

The motion model is fitted by least squares to the offline data sets, whose observations
are noise-free (``fit_motion_model``), on the steps that command less than 1 cm (the
precision phases; ``PRECISION_COMMAND``): the arm moves 0.862 of this step's command plus
0.223 of the previous one (the servos carry velocity over). The residual is about 3.5 mm
per step and axis there; with 2 cm reading noise the steady-state Kalman gain for that ratio
is 0.16. The default gain stays 0.2 (the Kalman gain for the 4.5 mm residual before the
joint-speed limit; docs/results.md compares gains). For white reading noise of std sigma
the estimate's std is ``sigma * sqrt(g / (2 - g))`` (0.33 sigma at g = 0.2). The filter
uses nothing but what the policy already sees and does: no joint readings. Orientation and
gripper features pass through unchanged (they carry no noise in this project's noise model).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from osg_control.json_files import is_json_number

DEFAULT_GAIN = 0.2
"""Blend of each new reading: about the steady-state Kalman gain for the motion model's
residual against 2 cm reading noise (0.2 for 4.5 mm, 0.24 for 5.5 mm; see the module
docstring and docs/results.md)."""
MOTION_MODEL = (0.862, 0.223)
"""TCP displacement per step = ``k_now * command_t + k_prev * command_{t-1}``, fitted with
``fit_motion_model`` on the steps under ``PRECISION_COMMAND`` of the kitchen's nineteen
default data sets (seed 0, 300 episodes each), with the speed-limited servo
(``control.servo``; before it, on every step: 0.875 and 0.24). The default of a defaults
folder that records none: each domain's pipeline fits its own on its data and ships it in
the manifest (``motion_model``), which the executor then uses."""
MOTION_BOUND = 2.0
"""The largest magnitude of a motion model's coefficient: a step moves the TCP by about the
commanded displacement (``k_now + k_prev`` near 1); a manifest of ``[1e300, 1e300]`` made
every estimate non-finite."""
PRECISION_COMMAND = 0.01
"""The motion model is fitted on steps that command less than 1 cm: the approaches and
grasps, where the filtered estimate decides where to close. Longer commands are slowed by
the joint-speed limit (fitted alone, 1-2 cm steps give k_now 0.77 and 2-5 cm steps 0.64,
against 0.86 below 1 cm); a model fitted on every step (0.682, 0.259) made the filter lag
the slow phases (its cost on Tables IV/V: docs/results.md)."""


def fit_motion_model(
    observations: np.ndarray,
    actions: np.ndarray,
    next_observations: np.ndarray,
    episode_starts: np.ndarray,
    max_command: float = PRECISION_COMMAND,
) -> tuple[float, float]:
    """Least-squares ``(k_now, k_prev)`` of TCP displacement on this and the last command.

    Args:
        observations, actions, next_observations: (N, 10), (N, 7), (N, 10) noise-free
            transitions, episodes concatenated.
        episode_starts: indices of each episode's first transition (no previous command).
        max_command: fit on the steps whose position command is shorter than this [m]
            (see ``PRECISION_COMMAND``).

    Returns:
        The two coefficients, shared by the three axes.
    """
    command = np.asarray(actions, dtype=float)[:, :3]
    previous = np.vstack([np.zeros((1, 3)), command[:-1]])
    previous[np.asarray(episode_starts, dtype=int)] = 0.0
    displacement = np.asarray(next_observations)[:, :3] - np.asarray(observations)[:, :3]
    small = np.linalg.norm(command, axis=1) < max_command
    design = np.stack([command[small].ravel(), previous[small].ravel()], axis=1)
    (k_now, k_prev), *_ = np.linalg.lstsq(design, displacement[small].ravel(), rcond=None)
    return float(k_now), float(k_prev)


def check_motion_model(motion: object) -> tuple[float, float]:
    """``motion`` as ``(k_now, k_prev)``.

    Raises:
        ValueError: not two finite numbers within ``MOTION_BOUND``, naming the value.
    """
    if not (
        isinstance(motion, list | tuple)
        and len(motion) == 2
        and all(is_json_number(k) and abs(k) <= MOTION_BOUND for k in motion)
    ):
        raise ValueError(
            f"a motion model must be two finite numbers within +-{MOTION_BOUND:g} "
            f"(k_now, k_prev), got {motion!r}"
        )
    return float(motion[0]), float(motion[1])


class TcpFilter:
    """Recursive TCP position estimate; ``reset`` at the start of every episode."""

    def __init__(
        self, gain: float = DEFAULT_GAIN, motion: tuple[float, float] = MOTION_MODEL
    ) -> None:
        """Args:
        gain: weight in (0, 1] of a new reading (1 = no filtering).
        motion: ``(k_now, k_prev)``, see ``MOTION_MODEL``.

        Raises:
            ValueError: a gain outside (0, 1] (NaN, a bool or a string included), or a
                motion model that is not two finite numbers within ``MOTION_BOUND``.
        """
        if not (is_json_number(gain) and 0.0 < gain <= 1.0):
            raise ValueError(f"filter gain must be a number in (0, 1], got {gain!r}")
        check_motion_model(motion)
        self.gain = gain
        self.motion = motion
        self._estimate: np.ndarray | None = None
        self._previous_command = np.zeros(3)

    def reset(self) -> None:
        """Forget the estimate: the next reading is taken as it is."""
        self._estimate = None
        self._previous_command = np.zeros(3)

    def forget_motion(self) -> None:
        """Keep the estimate but drop the previous command (the arm is at rest)."""
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


class TcpTracker:
    """A ``TcpFilter`` wired to one control loop: ``read`` every observation, tell it every
    action applied (``acted``); it pairs each reading with the actions since the last one.

    Reading the same observation twice with no action in between returns the same
    estimate (the executor reads the last observation of a skill to plan, and the next
    skill starts from it); a new reading with no action (after the joint reset, which holds
    the TCP still) is folded in as a reading of a resting arm.
    """

    def __init__(
        self, gain: float = DEFAULT_GAIN, motion: tuple[float, float] = MOTION_MODEL
    ) -> None:
        self.filter = TcpFilter(gain, motion)
        self._pending: np.ndarray | None = None
        self._last_reading: np.ndarray | None = None
        self._last_seen: np.ndarray | None = None

    def reset(self) -> None:
        """Start a new episode."""
        self.filter.reset()
        self._pending = self._last_reading = self._last_seen = None

    def read(self, obs: np.ndarray) -> np.ndarray:
        """The observation with its position replaced by the filtered estimate."""
        last, last_reading = self._last_seen, self._last_reading
        if (
            self._pending is None
            and last is not None
            and last_reading is not None
            and np.array_equal(obs, last_reading)
        ):
            return last.copy()
        self._last_seen = self.filter.update(obs, self._pending)
        self._last_reading = np.array(obs, dtype=float)
        self._pending = None
        return self._last_seen.copy()

    def settle(self) -> None:
        """The arm was brought to rest (the joint reset between skills): forget the commands
        since the last reading and the servo lag they carried.

        Folding the last command of the finished skill into the next reading instead (what
        the motion model says) was measured worse: pick-up-place at sigma = 2 cm, no
        replanning, 200 episodes: 0.81 against 0.875 (docs/results.md).
        """
        self._pending = None
        self.filter.forget_motion()

    def acted(self, action: np.ndarray) -> None:
        """Record the action just applied (the next reading is taken after it)."""
        self._pending = np.asarray(action, dtype=float)


class FilteredPolicy:
    """A policy that acts on filtered observations; one instance per episode."""

    def __init__(
        self,
        policy: Callable[[np.ndarray], np.ndarray],
        gain: float,
        motion: tuple[float, float] = MOTION_MODEL,
    ) -> None:
        self.policy = policy
        self.tracker = TcpTracker(gain, motion)

    def reset(self) -> None:
        """Start a new episode."""
        self.tracker.reset()

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        """The wrapped policy's action for the filtered observation."""
        action = self.policy(self.tracker.read(obs))
        self.tracker.acted(action)
        return action
