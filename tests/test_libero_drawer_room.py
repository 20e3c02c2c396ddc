"""A place into a drawer pulled out less than the held bowl is wide (the ``libero``
extra, skipped without it): the bowl is set down at the front of the drawer, in the part
open from above, not at the region's centre, whose far half lies under the handles of the
drawers above (LIBERO-10 task 3 state 13: the bowl came down on one and tipped in)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import episode_start  # noqa: E402

from osg_control.libero.facts import region_pose  # noqa: E402
from osg_control.libero.spots import surface  # noqa: E402

DRAWER = "white_cabinet_1_bottom_region"
BOWL = "akita_black_bowl_1"


def test_the_bowl_goes_in_front_of_the_handles_above() -> None:
    """Along the drawer's pull, the bowl is set down at least 1.5 cm further out than the
    region's centre (its far side then clears the handle above: its front, 1.7 cm before
    its centre, stands 2.7 cm further out than the far side at the centre), and its near
    side reaches at most 5 mm over the drawer's front edge (it lacks 6 mm of room)."""
    start = episode_start("libero_10", 3, 13)
    ctx, percept, scene = start.ctx, start.percept, start.ctx.scene
    joint = scene.joints[str(scene.regions[DRAWER].joint)]
    out = joint.outward  # the drawer's pull, out of the cabinet
    spot = float(surface(ctx, percept, DRAWER, True, BOWL) @ out)
    half = float(np.max(scene.extents[BOWL][1][:2] - scene.extents[BOWL][0][:2])) / 2
    pos, mat = region_pose(scene, percept, DRAWER)
    centre = float(pos @ out)
    front = centre + float(np.abs(mat @ scene.regions[DRAWER].size) @ np.abs(out))
    assert spot > centre + 0.015
    assert spot + half < front + 0.005
