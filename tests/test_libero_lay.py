"""An object too tall for the drawer it goes into (the ``libero`` extra, skipped without
it): LIBERO-PRO's ``libero_10_task`` task 3 puts the 15.8 cm wine bottle in a bottom
drawer whose region is 6 cm high. Stood upright there it stopped the drawer closing; it is
stood in the corner of the drawer's open part nearer the arm and the front, let go, and
pushed over toward the far corner so that it lies across the drawer."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import episode_start, scripted_episode  # noqa: E402

from osg_control.libero.facts import region_pose  # noqa: E402
from osg_control.libero.lay import across, lay, lies_down, push_over  # noqa: E402
from osg_control.libero.spots import surface  # noqa: E402
from osg_control.libero.tall import neck_grasps  # noqa: E402

BOTTLE, DRAWER = "wine_bottle_1", "white_cabinet_1_bottom_region"


def test_the_bottle_lies_down_in_the_bottom_drawer_and_the_bowl_does_not() -> None:
    """The bottle stands taller than the drawer's box and, lying, fits it; LIBERO-10's
    bowl into the same drawer stands in it; a region without a drawer is never one."""
    start = episode_start("libero_10_task", 3, 40)
    assert lies_down(start.ctx, BOTTLE, DRAWER)
    assert not lies_down(start.ctx, BOTTLE, "wine_rack_1_top_region")
    bowl = episode_start("libero_10", 3, 0)
    assert not lies_down(bowl.ctx, "akita_black_bowl_1", DRAWER)


def test_the_bottle_stands_in_the_near_corner_and_falls_toward_the_far_one() -> None:
    """The spot ``surface`` gives is the stand of ``lay``: inside the region's box, on the
    arm's side of its centre and nearer the drawer's front; the fall points away from the
    arm and into the drawer, and the bottle tipped over its bottom's edge (its height and
    radius from where it stood) ends inside the box. Its pick takes it at the neck."""
    start = episode_start("libero_10_task", 3, 40)
    ctx, percept = start.ctx, start.percept
    box = ctx.scene.regions[DRAWER]
    joint = ctx.scene.joints[str(box.joint)]
    out = joint.outward
    way = across(ctx, DRAWER)
    assert abs(way @ joint.axis) < 1e-9 and way[:2] @ (box.pos[:2] - ctx.base_xy[:2]) > 0.0
    spot = surface(ctx, percept, DRAWER, True, BOTTLE)
    laid = lay(ctx, percept, BOTTLE, DRAWER)
    assert np.allclose(spot[:2], laid.stand[:2])
    centre, mat = region_pose(ctx.scene, percept, DRAWER)
    half = np.abs(mat @ box.size)
    assert np.all(np.abs(spot[:2] - centre[:2]) < half[:2])
    assert (spot - centre) @ way < 0.0 < (spot - centre) @ out
    fall = laid.fall(laid.stand)
    assert fall @ way > 0.0 and fall @ out < 0.0
    low, high = ctx.scene.extents[BOTTLE]
    radius = float(np.max(np.abs(np.r_[low[:2], high[:2]])))
    top = laid.stand + fall * (radius + high[2] - low[2])
    assert np.all(np.abs(top[:2] - centre[:2]) <= half[:2])
    grasps = neck_grasps(ctx, [("pick", (BOTTLE, "x")), ("place-in", (BOTTLE, DRAWER))])
    assert BOTTLE in grasps


def test_the_push_goes_past_the_bottles_axis_across_the_drawer() -> None:
    """The push leg's target lies past where the bottle stands along the fall, at the
    height of its upper part, after a leg beside it on the near side."""
    start = episode_start("libero_10_task", 3, 40)
    ctx, percept = start.ctx, start.percept
    way = lay(ctx, percept, BOTTLE, DRAWER).fall(percept.position(BOTTLE))
    over, down, push, _ = push_over(ctx, BOTTLE, DRAWER)
    standing = percept.position(BOTTLE)
    beside, _ = down.target(percept, percept)
    pushed, _ = push.target(percept, percept)
    assert (beside - standing) @ way < 0.0 < (pushed - standing) @ way
    assert beside[2] - standing[2] > 0.5 * ctx.scene.extents[BOTTLE][1][2]


@pytest.mark.slow
def test_the_bottle_lies_in_the_closed_drawer(capsys) -> None:
    """State 40 within its 520 steps, no operator failed (at 5b83ccf the standing bottle
    stopped the drawer's close)."""
    episode = scripted_episode(capsys, "libero_10_task", 3, 40)
    assert episode["success"], episode["trace"]
    assert not any("FAILED" in line for line in episode["trace"])
