"""A bowl on the table under a drawer pulled out over it (the ``libero`` extra, skipped
without it; LIBERO-Goal task 3 state 0, the top drawer sensed open): its rim grasp leans
the hand away from the drawer, and the grasped bowl slides out from under it across the
fingers before the lift; with the drawer shut, neither (the hand comes straight down); a
bowl beside the open drawer, not under it, is not slid."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import episode_start  # noqa: E402

from osg_control.libero.clearance import footprint  # noqa: E402
from osg_control.libero.grasp import grasp_rotation  # noqa: E402
from osg_control.libero.legs import Context  # noqa: E402
from osg_control.libero.overhang import (  # noqa: E402
    SLIDE_MARGIN,
    UNDER_MARGIN,
    overhangs,
    slide,
)
from osg_control.libero.perception import LiberoPercept  # noqa: E402

BOWL = "akita_black_bowl_1"
JOINT = "wooden_cabinet_1_top_level"


def _scene(travel: float) -> tuple[Context, LiberoPercept]:
    start = episode_start("libero_goal", 3)
    ctx, percept = start.ctx, start.percept
    fixtures = dict(percept.fixtures)
    fixtures[JOINT] = dataclasses.replace(fixtures[JOINT], value=travel)
    return ctx, dataclasses.replace(percept, fixtures=fixtures)


def test_a_bowl_under_an_open_drawer_is_grasped_leaning_and_slid_out() -> None:
    """Open (at its stop, -0.16 m): the hand leans about 25 deg from vertical (the start's
    hand is 2 deg off), its palm's top away from the drawer's box; the slide moves the
    bowl across the fingers until its footprint is ``SLIDE_MARGIN`` clear of that box."""
    ctx, percept = _scene(-0.16)
    low, high = max(overhangs(ctx, percept, BOWL), key=lambda box: float(box[0][2]))
    hand = grasp_rotation(ctx, percept, BOWL)
    away = (percept.position(BOWL) - (low + high) / 2)[:2]
    assert np.degrees(np.arccos(-hand[2, 2])) == pytest.approx(25.0, abs=3.0)
    assert float(-hand[:2, 2] @ away) > 0.0
    ctx.rotation = hand
    tcp, _ = slide(ctx, BOWL).target(percept, percept)
    shift = tcp - percept.tcp
    assert abs(float(shift @ hand[:, 1])) < 1e-9  # across the fingers
    box = footprint(ctx, percept, BOWL) + shift[:2]
    gaps = np.r_[low[:2] - box[1], box[0] - high[:2]]
    assert gaps.max() == pytest.approx(SLIDE_MARGIN, abs=1e-6)


def test_a_shut_drawer_changes_nothing() -> None:
    """Shut, no drawer's box is over the bowl: the grasp is top-down, no slide."""
    ctx, percept = _scene(0.0)
    assert grasp_rotation(ctx, percept, BOWL)[2, 2] == pytest.approx(-1.0, abs=0.02)
    tcp, _ = slide(ctx, BOWL).target(percept, percept)
    assert np.array_equal(tcp, percept.tcp)


def _beside(ctx: Context, percept: LiberoPercept, gap: float) -> LiberoPercept:
    """``percept`` with the bowl moved straight out from under the drawer over it until its
    footprint is ``gap`` clear of the drawer's box, seen from above."""
    low, high = max(overhangs(ctx, percept, BOWL), key=lambda box: float(box[0][2]))
    box = footprint(ctx, percept, BOWL)
    away = percept.position(BOWL)[:2] - (low + high)[:2] / 2
    axis = int(np.argmax(np.abs(away)))
    side = np.sign(away[axis])
    edge = high[axis] if side > 0 else low[axis]  # the drawer's side the bowl leaves by
    near = box[0][axis] if side > 0 else box[1][axis]  # the bowl's side facing it
    shift = np.zeros(3)
    shift[axis] = edge - near + side * gap
    pos, rot = percept.objects[BOWL]
    return dataclasses.replace(percept, objects={**percept.objects, BOWL: (pos + shift, rot)})


@pytest.mark.parametrize("gap, slides", [(UNDER_MARGIN / 2, True), (2 * UNDER_MARGIN, False)])
def test_only_a_bowl_under_a_drawer_is_slid(gap: float, slides: bool) -> None:
    """A bowl within ``UNDER_MARGIN`` of the open drawer's footprint is slid out; one
    farther beside it (LIBERO-Spatial task 6's, 2.3-3.5 cm from the cabinet's drawers) is
    lifted where it stands."""
    ctx, percept = _scene(-0.16)
    ctx.rotation = grasp_rotation(ctx, percept, BOWL)
    moved = _beside(ctx, percept, gap)
    tcp, _ = slide(ctx, BOWL).target(moved, moved)
    assert np.array_equal(tcp, moved.tcp) is not slides
