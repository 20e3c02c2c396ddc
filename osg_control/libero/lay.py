"""The lay-down of an object too tall for the drawer it goes into: stood in the corner of
the drawer's open part nearer the arm and the drawer's front, let go, and pushed over at
its upper part toward the drawer's far corner, so that it lies across the drawer, under
the cabinet's closed height.

LIBERO-PRO's ``libero_10_task`` task 3 puts the 15.8 cm wine bottle in a bottom drawer
whose region's box is 6 cm high: stood upright in it, the bottle stopped the drawer from
closing (0 / 10). Lying, it is 4.4 cm high; tipped over its bottom's edge it reaches 18 cm
from where it stood, more than the drawer's 20 cm width leaves from a wall (pushed
straight across, it leant on the far wall at 74 deg and stopped the close), less than its
diagonal. The object is taken at its neck for it (``tall.neck_grasps``: the top-down grasp
near its bottom brought the palm down on its top).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from osg_control.libero.clearance import HAND_BOXES
from osg_control.libero.drive import GRIPPER_CLOSED
from osg_control.libero.facts import region_pose, room
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


@dataclass(frozen=True)
class Lay:
    """Where the object stands before it is pushed over (its origin's world ``stand``) and
    the point it is pushed over toward (``toward``: its top's axis ends near it)."""

    stand: np.ndarray
    toward: np.ndarray

    def fall(self, standing: np.ndarray) -> np.ndarray:
        """The horizontal unit direction an object standing at ``standing`` is pushed."""
        way = (self.toward - standing) * np.array([1.0, 1.0, 0.0])
        return way / np.linalg.norm(way)


def lies_down(ctx: Context, obj: str, region: str) -> bool:
    """Whether ``obj`` goes into the drawer region ``region`` lying: it stands taller than
    the region's box and, lying, is lower than it."""
    box = ctx.scene.regions.get(region)
    if box is None or box.joint is None:
        return False
    low, high = ctx.scene.extents[obj]
    height, width = float(high[2] - low[2]), float(np.max(high[:2] - low[:2]))
    box_height = 2.0 * float(np.abs(box.mat[2]) @ box.size)
    return height > box_height > width


def across(ctx: Context, region: str) -> np.ndarray:
    """The horizontal direction across the drawer ``region``'s pull, pointing away from
    the arm's base."""
    box = ctx.scene.regions[region]
    pull = ctx.scene.joints[str(box.joint)].axis
    way = np.cross([0.0, 0.0, 1.0], pull)
    way /= np.linalg.norm(way)
    return way if way[:2] @ (box.pos[:2] - ctx.base_xy[:2]) >= 0.0 else -way


def _radius(ctx: Context, obj: str) -> float:
    low, high = ctx.scene.extents[obj]
    return float(np.max(np.abs(np.r_[low[:2], high[:2]])))


def lay(ctx: Context, percept: LiberoPercept, obj: str, region: str) -> Lay:
    """Where ``obj`` stands in the drawer ``region`` at its sensed travel: in the corner of
    the part open from above (``facts.room``) nearer the arm's base and the drawer's
    front, its footprint ``LAY_MARGIN`` inside; pushed over toward the region box's far
    corner (the cabinet's side, away from the arm), its footprint as far inside."""
    box = ctx.scene.regions[region]
    joint = ctx.scene.joints[str(box.joint)]
    out = joint.outward  # toward the drawer's front
    way = across(ctx, region)
    pos, mat = region_pose(ctx.scene, percept, region)
    half_way = float(np.abs(way @ mat) @ box.size)
    half_out = float(np.abs(out @ mat) @ box.size)
    inset = _radius(ctx, obj) + LAY_MARGIN
    _, front = room(ctx.scene, percept, region)
    stand = pos - way * (half_way - inset)
    stand = stand + out * (front - inset - float(stand @ out))
    far = pos + way * (half_way - inset) - out * (half_out - inset)
    return Lay(stand, far)


def push_over(ctx: Context, obj: str, region: str) -> list[Leg]:
    """After ``obj`` was let go standing in ``region`` (``lay``): the closed hand, its palm
    across the push and moved along itself toward the drawer's front until its inner end
    lies ``PALM_OVERLAP`` past the object's axis (centred on it, the palm's 21 cm reached
    the cabinet's top drawer and stopped the push at 10 deg), over beside the object at the
    height it was left at, down until the palm's lower face is ``PUSH_HEIGHT`` up it,
    ``PUSH_PAST`` past its axis with the palm's side, and up."""
    joint = ctx.scene.joints[str(ctx.scene.regions[region].joint)]
    out = joint.outward
    low, high = ctx.scene.extents[obj]
    reach, half_width, palm = HAND_BOXES[0]
    side = _radius(ctx, obj) + half_width + PUSH_GAP
    height = float(low[2] + PUSH_HEIGHT * (high[2] - low[2])) - palm
    push: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # beside, fall, hand

    def beside(now: LiberoPercept) -> np.ndarray:
        if not push:  # decided once, where the object was let go
            standing = now.position(obj)
            fall = lay(ctx, now, obj, region).fall(standing)
            along = np.cross([0.0, 0.0, 1.0], fall)  # the palm's long axis
            along = along if along @ out >= 0.0 else -along
            point = standing - fall * side + along * (reach - PALM_OVERLAP)
            push.append((point + np.array([0.0, 0.0, height]), fall, fingers_along(ctx, along)))
        return push[0][0]

    def over(now: LiberoPercept, first: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        point = beside(now)
        return np.r_[point[:2], max(point[2], first.tcp[2])], push[0][2]

    def down(now: LiberoPercept, first: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        return beside(now), push[0][2]

    def across_axis(now: LiberoPercept, first: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        return beside(now) + push[0][1] * (side + PUSH_PAST), push[0][2]

    return [Leg(over, GRIPPER_CLOSED, 40, 0.01, transit=True), Leg(down, GRIPPER_CLOSED, 30, 0.01),
            Leg(across_axis, GRIPPER_CLOSED, 40, 0.01), up(0.08, GRIPPER_CLOSED)]  # fmt: skip
