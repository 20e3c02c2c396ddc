"""The grasp of a tall object the plan sets on a region's top, or lays down in a drawer
(``lay``): below its top, the palm clear of it, so that it hangs upright from the hand.

The top-down grasp (``grasp.grips``) closes at most ``GRASP_FLOOR`` above an object's
bottom; on an object that rises more than the palm's height above that point (the wine
bottle: 15.8 cm tall, its 1 cm neck from 5 cm up) the palm (``clearance.HAND_BOXES``, its
lower face 2.6 cm above the TCP) comes down on its top and tips it: the fingers close on
it leaning 35-65 deg, or the descent stalls on it and the pick fails (LIBERO-Goal tasks 2
and 9, half their picks). Leaning, it stopped on the wine rack's slot (62 deg from level)
with its origin outside the slot, or fell off it. When the plan sets such an object on a
region's top next, its pick takes it where the palm clears its top (``neck_grasps``, set
on the episode's ``Context.grasps`` like ``insert.doorway_grasps``); it hangs upright, 13
cm below the hand, and the carry rises for it (``pick_place.HELD_CLEARANCE``); so when it
goes into a drawer it is laid down in. Another place into a region (LIBERO-Object's bottles
into the basket, 497 / 500 with the low grasp) keeps the low grasp: not tried there.
"""

from __future__ import annotations

import numpy as np

from osg_control.libero.clearance import HAND_BOXES
from osg_control.libero.grasp import GRIP_WIDTH, grip
from osg_control.libero.lay import lies_down
from osg_control.libero.legs import Context, GraspRule, Step, first_places
from osg_control.libero.perception import LiberoPercept

PALM_GAP = 0.005
"""How far the palm's lower face keeps above the object's top at a neck grasp [m]."""


def neck_height(ctx: Context, obj: str) -> float | None:
    """The height above ``obj``'s origin the TCP closes at for the palm to stand
    ``PALM_GAP`` above its top, when the palm at the preferred grasp (``grasp.grip``) would
    be below its top and every part at that height fits the open hand; else None."""
    high = ctx.scene.extents[obj][1]
    palm = HAND_BOXES[0][2]
    if grip(ctx, obj).point[2] + palm >= high[2]:
        return None  # the palm clears the top already
    z = float(high[2]) - palm - PALM_GAP
    finger_bottom = z + HAND_BOXES[-1][2]
    parts = [(lo, hi) for lo, hi in ctx.scene.parts[obj] if hi[2] > finger_bottom and lo[2] < z]
    if not parts or any(max(hi[a] for _, hi in parts) - min(lo[a] for lo, _ in parts)
                        > GRIP_WIDTH for a in (0, 1)):  # fmt: skip
        return None
    return z


def neck_grasp(ctx: Context, obj: str, height: float) -> GraspRule:
    """The grasp ``height`` above ``obj``'s origin on its upright axis, the hand as for
    a round object (the start's top-down rotation)."""

    def rule(percept: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        pos, rot = percept.objects[obj]
        return pos + rot @ np.array([0.0, 0.0, height]), ctx.base

    return rule


def neck_grasps(ctx: Context, steps: list[Step]) -> dict[str, GraspRule]:
    """The grasps a plan's ``steps`` need: for each object whose next place is on a
    region's top, or into a drawer it is laid down in (``lay``), and whose top the palm
    would land on, ``neck_grasp``."""
    grasps: dict[str, GraspRule] = {}
    for operator, obj, target in first_places(steps):
        on_region = operator == "place-on" and target in ctx.scene.regions
        laid = operator == "place-in" and lies_down(ctx, obj, target)
        height = neck_height(ctx, obj) if on_region or laid else None
        if height is not None:
            grasps[obj] = neck_grasp(ctx, obj, height)
    return grasps
