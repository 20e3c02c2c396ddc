"""The lay-down of an object too tall for the drawer it goes into: stood at the end of the
drawer's width nearer the arm, let go, and pushed over at its upper part so that it lies
along the width, under the cabinet's closed height.

LIBERO-PRO's ``libero_10_task`` task 3 puts the 15.8 cm wine bottle in a bottom drawer
whose region's box is 6 cm high: stood upright in it, the bottle stopped the drawer from
closing (0 / 10). Lying, it is 4.4 cm high and fits the drawer's 20 cm width. The object
is taken at its neck for it (``tall.neck_grasps``): the top-down grasp near its bottom
brought the palm down on its top.
"""

from __future__ import annotations

import numpy as np

from osg_control.libero.clearance import HAND_BOXES
from osg_control.libero.drive import GRIPPER_CLOSED
from osg_control.libero.grasp import fingers_along
from osg_control.libero.legs import Context, Leg, up
from osg_control.libero.perception import LiberoPercept

LAY_MARGIN = 0.01
"""How far inside the region's box the object keeps, stood and lying [m]."""
PUSH_HEIGHT = 0.8
"""Where on the object the palm pushes it over: this fraction of its height up."""
PUSH_GAP = 0.01
"""The gap between the hand's side and the object before the push [m]."""
PALM_OVERLAP = 0.02
"""How far past the object's axis, toward the cabinet, the palm's inner end reaches [m]."""
PUSH_PAST = 0.06
"""How far past the object's axis the hand pushes [m]."""


def lies_down(ctx: Context, obj: str, region: str) -> bool:
    """Whether ``obj`` goes into the drawer region ``region`` lying: it stands taller than
    the region's box, and lying across the drawer it is lower than the box and fits its
    width (``LAY_MARGIN`` at each end)."""
    box = ctx.scene.regions.get(region)
    if box is None or box.joint is None:
        return False
    low, high = ctx.scene.extents[obj]
    height, width = float(high[2] - low[2]), float(np.max(high[:2] - low[:2]))
    box_height = 2.0 * float(np.abs(box.mat[2]) @ box.size)
    return (
        height > box_height
        and width < box_height
        and height < 2.0 * (_half_across(ctx, region) - LAY_MARGIN)
    )


def across(ctx: Context, region: str) -> np.ndarray:
    """The horizontal direction across the drawer ``region``'s pull, pointing away from
    the arm's base (the way the object is pushed over)."""
    box = ctx.scene.regions[region]
    pull = ctx.scene.joints[str(box.joint)].axis
    way = np.cross([0.0, 0.0, 1.0], pull)
    way /= np.linalg.norm(way)
    return way if way[:2] @ (box.pos[:2] - ctx.base_xy[:2]) >= 0.0 else -way


def _half_across(ctx: Context, region: str) -> float:
    box = ctx.scene.regions[region]
    return float(np.abs(across(ctx, region) @ box.mat) @ box.size)


def _radius(ctx: Context, obj: str) -> float:
    low, high = ctx.scene.extents[obj]
    return float(np.max(np.abs(np.r_[low[:2], high[:2]])))


def stand_offset(ctx: Context, obj: str, region: str) -> np.ndarray:
    """Where ``obj`` stands before it is pushed over, from the region's centre: at the end
    of its width nearer the arm, ``LAY_MARGIN`` inside."""
    reach = _half_across(ctx, region) - _radius(ctx, obj) - LAY_MARGIN
    return -across(ctx, region) * reach


def push_over(ctx: Context, obj: str, region: str) -> list[Leg]:
    """After ``obj`` was let go standing in ``region``: the closed hand, its fingers along
    the drawer's pull and moved out toward its front until the palm's inner end lies
    ``PALM_OVERLAP`` past the object's axis (centred on it, the palm's 21 cm reached the
    cabinet's top drawer and stopped the push at 10 deg), over beside it at the height it
    was left at, down until the palm's lower face is ``PUSH_HEIGHT`` up it, across its axis
    by ``PUSH_PAST`` with the palm's side, up, and the hand turned back to the start's
    (left along the pull, the drawer's close turned it from there while the IK swung the
    arm into the cabinet)."""
    way = across(ctx, region)
    joint = ctx.scene.joints[str(ctx.scene.regions[region].joint)]
    out = joint.axis * joint.opening  # toward the drawer's front
    low, high = ctx.scene.extents[obj]
    reach, half_width, palm = HAND_BOXES[0]
    side = _radius(ctx, obj) + half_width + PUSH_GAP
    offset = -way * side + out * (reach - PALM_OVERLAP)
    offset[2] = float(low[2] + PUSH_HEIGHT * (high[2] - low[2])) - palm
    hand = fingers_along(ctx, out)
    start: list[np.ndarray] = []  # where the object stood when the push began

    def beside(now: LiberoPercept) -> np.ndarray:
        if not start:
            start.append(now.position(obj))
        return start[0] + offset

    def over(now: LiberoPercept, first: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        point = beside(now)
        return np.r_[point[:2], max(point[2], first.tcp[2])], hand

    def down(now: LiberoPercept, first: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        return beside(now), hand

    def push(now: LiberoPercept, first: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        return beside(now) + way * (side + PUSH_PAST), hand

    return [Leg(over, GRIPPER_CLOSED, 40, 0.01, transit=True), Leg(down, GRIPPER_CLOSED, 30, 0.01),
            Leg(push, GRIPPER_CLOSED, 40, 0.01), up(0.08, GRIPPER_CLOSED),
            Leg(lambda now, first: (first.tcp, ctx.base), GRIPPER_CLOSED, 40, 0.01,
                transit=True)]  # fmt: skip
