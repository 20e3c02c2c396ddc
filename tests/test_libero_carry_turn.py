"""Turning a held object's grasped slice out through a doorway (the ``libero`` extra,
skipped without it): LIBERO-PRO's ``libero_10_task`` task 9 puts the porcelain mug into the
microwave, and the only slice of it that fits the hand, its handle, faces away from the
doorway; carried as grasped, the hand would lead into the microwave. The hand turns half a
turn the way the wrist's window allows; LIBERO-10's mug, its handle already out, is not
turned."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import episode_start  # noqa: E402

from osg_control.libero.grasp import in_turn_window, turned_from_start  # noqa: E402
from osg_control.libero.insert import carry_turn, doorway, doorway_grasp  # noqa: E402

REGION = "microwave_1_heating_region"


def _turned(vector: np.ndarray, angle: float) -> np.ndarray:
    """``vector``'s horizontal part turned ``angle`` about the vertical."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([c * vector[0] - s * vector[1], s * vector[0] + c * vector[1]])


@pytest.mark.parametrize(
    ("suite", "mug", "half_turn"),
    [("libero_10_task", "porcelain_mug_1", True), ("libero_10", "white_yellow_mug_1", False)],
)
def test_the_grasped_slice_is_turned_out_through_the_doorway(
    suite: str, mug: str, half_turn: bool
) -> None:
    """The doorway grasp's hand turns, within the wrist's window, until the grasped slice
    faces out along the doorway's normal: by half a turn for the porcelain mug's handle,
    by nothing for LIBERO-10's mug."""
    start = episode_start(suite, 9)
    ctx, percept = start.ctx, start.percept
    way = doorway(ctx.scene, REGION)
    point, hand = doorway_grasp(ctx, mug, way)(percept)
    facing = point - percept.position(mug)
    end = carry_turn(ctx, hand, facing, way)
    assert end is not None and in_turn_window(end)
    turn = end - turned_from_start(ctx, hand)
    assert abs(abs(turn) - np.pi) < 0.1 if half_turn else abs(turn) < 0.05
    out = _turned(facing, turn)
    assert out @ way.normal[:2] / np.linalg.norm(out) > 0.99


def test_a_turn_past_the_wrists_window_is_refused() -> None:
    """A slice facing 100 deg clockwise of the doorway's normal: from the start's hand the
    turn back is within the wrist's window; from a hand already turned 100 deg
    counter-clockwise it is not, either way round (200 deg, or 160 the other way)."""
    start = episode_start("libero_10_task", 9)
    ctx = start.ctx
    way = doorway(ctx.scene, REGION)
    facing = np.r_[_turned(way.normal, -np.radians(100.0)), 0.0]
    turned = np.array([[np.cos(1.745), -np.sin(1.745), 0.0], [np.sin(1.745), np.cos(1.745), 0.0],
                       [0.0, 0.0, 1.0]]) @ ctx.base  # fmt: skip
    assert carry_turn(ctx, ctx.base, facing, way) == pytest.approx(np.radians(100.0), abs=1e-6)
    assert carry_turn(ctx, turned, facing, way) is None
