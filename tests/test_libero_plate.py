"""A plate (13.8 cm across, its rim 1.9 cm high) is grasped at its rim (the ``libero``
extra, skipped without it): on the side where the open hand stands clear of the cabinet,
the open fingers' lower faces ``RIM_FLOOR`` above its bottom; a held object is still
carried over its middle."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import episode_start  # noqa: E402

from osg_control.libero.clearance import HAND_BOXES, fixture_clearance  # noqa: E402
from osg_control.libero.grasp import (  # noqa: E402
    GRASP_CLEARANCE,
    RIM_FLOOR,
    RIM_INSET,
    grasp_point,
    grasp_rotation,
)
from osg_control.libero.pick_place import anchor  # noqa: E402

PLATE = "plate_1"


def test_a_plate_is_grasped_at_its_rim_nearer_the_arm() -> None:
    """LIBERO-Goal task 5 (the plate to the front of the stove), state 0: the grasp point
    is on the rim (its radius less ``RIM_INSET`` from the origin), on the side of the two
    on the fingers' axis where the open hand stands clear of the cabinet's boxes (on the
    other it reaches under the cabinet's front), the fingertips ``RIM_FLOOR`` above the
    plate's bottom; carrying something, the hand still makes for its middle."""
    start = episode_start("libero_goal", 5)
    ctx, percept, scene = start.ctx, start.percept, start.ctx.scene
    pos = percept.position(PLATE)
    low, high = scene.extents[PLATE]
    radius = float(min(np.abs(low[:2]).min(), np.abs(high[:2]).min())) - RIM_INSET
    point = grasp_point(ctx, percept, PLATE)
    assert np.linalg.norm(point[:2] - pos[:2]) == pytest.approx(radius)
    other = np.r_[2 * pos[:2] - point[:2], point[2]]  # the rim across the plate
    along = grasp_rotation(ctx, percept, PLATE)[:, 1]
    assert fixture_clearance(ctx, percept, point, along) >= GRASP_CLEARANCE
    assert fixture_clearance(ctx, percept, other, along) < 0.0
    assert point[2] + HAND_BOXES[1][2] == pytest.approx(pos[2] + low[2] + RIM_FLOOR)
    assert point[2] < pos[2] + high[2]  # the fingers reach round the rim
    assert np.linalg.norm(anchor(ctx, percept, PLATE, holding=True)[:2] - pos[:2]) < 1e-6
