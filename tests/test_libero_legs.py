"""The leg runner (``libero.legs.LegRunner``) on a fake percept stream: a transit leg that
stalls short of its target ends (LIBERO-Spatial task 6's bowl, out of the top-down hand's
reach: the arm stopped, or rocked about its stretched elbow), and one whose hand still
turns in place does not, though its TCP stands still, nor one whose target turns to
another; a careful leg waits out its steps as before."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.drive import GRIPPER_OPEN
from osg_control.libero.legs import STALL_STEPS, Leg, LegRunner

TARGET = np.array([0.141, -0.03, 1.031])
STEPS = 90
TURNED = Rotation.from_rotvec([0.0, 0.0, 2.0]).as_matrix()


def _commands(leg: Leg, stream: list[tuple[float, float]]) -> int:
    """How many commands the runner gives for ``leg`` on a stream of percepts, each the
    TCP that far short of ``TARGET`` [m] along x and the hand turned that far about z
    [rad] (the last joint), before it moves on (the stream's length when it never does)."""
    hand = lambda q: (None, Rotation.from_rotvec([0.0, 0.0, q[6]]).as_matrix())  # noqa: E731
    context: Any = SimpleNamespace(rotation=np.eye(3), driver=SimpleNamespace(tcp_pose=hand))
    runner = LegRunner([leg], context)
    for n, (short, turn) in enumerate(stream):
        percept = SimpleNamespace(joints=np.r_[np.zeros(6), turn], tcp=TARGET - [short, 0, 0])
        if runner.command(percept) is None:  # type: ignore[arg-type]
            return n
    return len(stream)


def _leg(transit: bool, rotation: np.ndarray | None = None) -> Leg:
    return Leg(lambda now, start: (TARGET, rotation), GRIPPER_OPEN, STEPS, 0.008, transit=transit)


def _closing_in(short: float) -> list[tuple[float, float]]:
    """Ten steps 1 cm apart, ending ``short`` of the target."""
    return [(short + 0.01 * (9 - k), 0.0) for k in range(10)]


def test_a_transit_leg_that_stops_short_ends() -> None:
    stopped = _closing_in(0.009) + [(0.009, 0.0)] * STEPS  # 9 mm short of 8 mm
    assert _commands(_leg(True), stopped) == 10 + STALL_STEPS - 1


def test_a_transit_leg_that_rocks_short_ends() -> None:
    rocking = _closing_in(0.0166) + [(0.0187, 0.0), (0.0166, 0.0)] * STEPS
    assert _commands(_leg(True), rocking) == 10 + STALL_STEPS - 1


def test_a_transit_leg_that_turns_in_place_goes_on() -> None:
    turning = [(0.0, 0.02 * k) for k in range(STEPS + 5)]  # toward TURNED, 2 rad off
    assert _commands(_leg(True, TURNED), turning) == STEPS


def test_a_transit_leg_whose_target_turns_is_watched_anew() -> None:
    """The grasp's rotation flips to its twin after 10 steps (LIBERO-Spatial task 4 state
    0): the hand, turned toward the first, is farther from the second than where it started,
    yet it turns on toward it and the leg ends there, near."""
    twins = [Rotation.from_rotvec([0.0, 0.0, a]).as_matrix() for a in (1.0, -1.01)]
    step = iter(range(STEPS))
    leg = Leg(lambda now, start: (TARGET, twins[next(step) >= 10]), GRIPPER_OPEN, STEPS,
              0.008, transit=True)  # fmt: skip
    hand = [(0.0, 0.02 * k) for k in range(11)] + [(0.0, 0.2 - 0.025 * k) for k in range(1, 60)]
    assert _commands(leg, hand) == 55  # within 0.1 rad of the second


def test_a_careful_leg_waits_out_its_steps() -> None:
    stopped = _closing_in(0.009) + [(0.009, 0.0)] * STEPS
    assert _commands(_leg(False), stopped) == STEPS
