"""The learned pick's close on a stalled descent (``libero.stall_close``): it closes only
once the open hand stopped coming closer over the grasp point, not while it descends, not
at the grasp point (the network's own close), not off to the side; and it keeps it closed."""

from __future__ import annotations

import numpy as np

from osg_control.libero.drive import GRIPPER_CLOSED, GRIPPER_OPEN
from osg_control.libero.pick_place import CLOSING_STEPS, DESCENT_TOLERANCE
from osg_control.libero.stall_close import LATERAL, STALL_STEPS, StallClose


def _run(offsets: list[tuple[float, float, float]], command: float = GRIPPER_OPEN) -> list[float]:
    rule = StallClose(DESCENT_TOLERANCE)
    return [rule.gripper(np.array(o), command) for o in offsets]


def test_a_descent_that_stops_above_the_grasp_point_closes_and_stays_closed() -> None:
    descent = [(0.0, 0.0, 0.15 - 0.01 * i) for i in range(6)]  # 1 cm a step
    stalled = [(0.003, 0.0, 0.09)] * (STALL_STEPS + 3)
    sent = _run(descent + stalled + [(0.0, 0.0, 0.05)])
    assert set(sent[: len(descent) + STALL_STEPS - 1]) == {GRIPPER_OPEN}
    assert set(sent[len(descent) + STALL_STEPS :]) == {GRIPPER_CLOSED}


def test_no_close_while_descending_at_the_grasp_point_or_off_to_the_side() -> None:
    descent = [(0.0, 0.0, 0.15 - 0.01 * i) for i in range(15)]
    at_point = [(0.0, 0.0, DESCENT_TOLERANCE / 2)] * 10
    aside = [(LATERAL + 0.005, 0.0, 0.03)] * 10
    assert set(_run(descent + at_point)) == {GRIPPER_OPEN}
    assert set(_run(aside)) == {GRIPPER_OPEN}


def test_no_close_on_a_pause_at_the_hover_before_the_descent() -> None:
    pause = [(0.001 * i, 0.0, 0.10 - 0.001 * i) for i in range(STALL_STEPS * 3)]
    assert set(_run(pause)) == {GRIPPER_OPEN}


def test_the_networks_own_close_is_passed_on() -> None:
    assert set(_run([(0.0, 0.0, 0.05)] * 10, GRIPPER_CLOSED)) == {GRIPPER_CLOSED}


def test_no_close_while_the_hand_closes_in_across_rising_a_little() -> None:
    """Its distance to the grasp point does not shrink, yet it is on its way (LIBERO-10
    task 2's moka pot, the pick starting 8 cm to the side)."""
    across = [(0.08 - 0.003 * i, 0.0, 0.12 + 0.001 * i) for i in range(28)]
    assert set(_run(across)) == {GRIPPER_OPEN}


def test_a_stalled_close_that_holds_nothing_has_missed() -> None:
    rule = StallClose(DESCENT_TOLERANCE)
    descent = [(0.0, 0.0, 0.15 - 0.01 * i) for i in range(6)]
    for offset in descent + [(0.003, 0.0, 0.09)] * (STALL_STEPS + 1):
        rule.gripper(np.array(offset), GRIPPER_OPEN)
    assert rule.closed and not rule.missed(holding=False)  # the fingers are still closing
    for _ in range(CLOSING_STEPS):
        rule.gripper(np.array((0.003, 0.0, 0.09)), GRIPPER_OPEN)
    assert rule.missed(holding=False) and not rule.missed(holding=True)
