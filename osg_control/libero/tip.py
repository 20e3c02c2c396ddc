"""The tip-over release: an object that another object the goal puts into the same region
will land on is let go turned onto its side, so that the one on it stands lower.

LIBERO's ``In`` reads an object's origin against the region's box. LIBERO-PRO's
``libero_10_object`` task 0 puts the 9.4 x 11.4 cm soup can and the 6.2 x 7.6 cm tomato
sauce into a basket 12.7 x 11.8 cm inside: they do not stand side by side, the can (pinched
at its edge, let go above the box, ``edge``) lands on what is there, and on the standing
sauce its origin stands 1.3 cm above the box. Lying, the sauce is 1.4 cm lower. The held
object is turned ``TIP_ANGLE`` about the fingers' axis just above the box, past the angle it
tips over at, and let go: it lands on its side.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.clearance import posed_corners
from osg_control.libero.drive import GRIPPER_CLOSED, GRIPPER_OPEN
from osg_control.libero.edge import pinched
from osg_control.libero.facts import region_pose
from osg_control.libero.legs import Context, Leg, Step, hold, up
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.rest import rest_heights
from osg_control.libero.scene import Solid

TIP_ANGLE = np.radians(60.0)
"""How far the hand turns the held object over before letting go [rad]: past the angle an
object taller than wide tips over at (atan(width / height) < 45 deg)."""
TIP_DROP = 0.02
"""How far above the region's box the turning object's lowest point keeps [m]."""
TIP_SAMPLES = 7
"""Angles from upright to ``TIP_ANGLE`` the turning object's lowest point is found over."""


def tipped(ctx: Context, percept: LiberoPercept, steps: list[Step]) -> frozenset[str]:
    """The objects a plan's ``steps`` put into a region that go in lying (``tips_over``):
    those another object is put into the same region after."""
    laid = set()
    for i, (operator, args) in enumerate(steps):
        if operator != "place-in":
            continue
        later = [a[0] for op, a in steps[i + 1 :] if op == "place-in" and a[1] == args[1]]
        if any(tips_over(ctx, percept, args[0], args[1], other) for other in later
               if other != args[0]):  # fmt: skip
            laid.add(args[0])
    return frozenset(laid)


def tips_over(ctx: Context, percept: LiberoPercept, obj: str, region: str, other: str) -> bool:
    """Whether ``obj`` goes into ``region`` lying, ``other`` to land on it after: on ``obj``
    standing over the region's centre, ``other``'s origin would stand above the region's
    box; ``obj`` stands taller than wide (lying lowers ``other`` by the difference) and lies
    within the box; it is not a drawer's region (``lay``) nor an object pinched at its edge
    (its grip already lies at the edge of the fingers' friction cones)."""
    box = ctx.scene.regions[region]
    if box.joint is not None or pinched(ctx, obj):
        return False
    low, high = ctx.scene.extents[obj]
    height, width = float(high[2] - low[2]), float(np.max(high[:2] - low[:2]))
    pos, mat = region_pose(ctx.scene, percept, region)
    half = np.abs(mat @ box.size)
    if not width < height <= 2.0 * float(np.min(half[:2])):
        return False
    standing = float(
        rest_heights(ctx, percept, obj, pos[None, :2], _floor(ctx, percept, region))[0]
    )
    standing = max(standing, float(pos[2] - half[2] - low[2]))  # nothing under it: the box
    other_origin = standing + float(high[2]) - float(ctx.scene.extents[other][0][2])
    return other_origin > pos[2] + half[2]


def _floor(ctx: Context, percept: LiberoPercept, region: str) -> list[Solid]:
    """The collision boxes of what carries ``region`` in the world: a movable object's at its
    perceived pose, a fixture's as read."""
    parent = ctx.scene.regions[region].parent
    if parent not in percept.objects:
        return ctx.scene.solids.get(parent, [])
    pos, rot = percept.objects[parent]
    return [Solid(pos + rot @ s.centre, rot @ s.rotation, s.half) for s in ctx.scene.shapes[parent]]


def release(
    ctx: Context, obj: str, region: str, over: Callable[[LiberoPercept], np.ndarray]
) -> list[Leg]:
    """From over the spot (``over``: the hand's point at the carrying height), down until
    ``obj``, turned ``TIP_ANGLE`` about the fingers' axis (its lower end toward the arm's
    base: turned the other way the hand rose 7 cm), keeps ``TIP_DROP`` above the region's
    box all the way; turn it at the arm's full pace (at the careful pace, the IK told the
    whole turn, the arm swung 20 cm aside), open, up, and turn the hand back upright."""
    turn: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # point, tipped, upright

    def decided(now: LiberoPercept) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if not turn:  # decided once, over the spot
            upright, point = ctx.rotation, over(now)
            pos, mat = region_pose(ctx.scene, now, region)
            top = float(pos[2] + np.abs(mat[2]) @ ctx.scene.regions[region].size)
            toward = np.r_[ctx.base_xy[:2] - point[:2], 0.0]
            angle = max((TIP_ANGLE, -TIP_ANGLE),
                        key=lambda a: float(_turned(upright, a)[:, 2] @ toward))  # fmt: skip
            hang = posed_corners(ctx, now, obj) + (now.position(obj) - now.tcp)  # about the TCP
            lowest = min(float(np.min(hang @ (_turned(upright, a) @ upright.T).T[:, 2]))
                         for a in np.linspace(0.0, angle, TIP_SAMPLES))  # fmt: skip
            hand = np.r_[point[:2], top + TIP_DROP - lowest]
            turn.append((hand, _turned(upright, angle), upright))
        return turn[0]

    return [Leg(lambda now, start: (decided(now)[0], None), GRIPPER_CLOSED, 40, 0.01),
            Leg(lambda now, start: decided(now)[:2], GRIPPER_CLOSED, 40, 0.01, transit=True),
            hold(GRIPPER_OPEN, 10), up(0.08, GRIPPER_OPEN),
            Leg(lambda now, start: (start.tcp, decided(now)[2]), GRIPPER_OPEN, 40, 0.01,
                transit=True)]  # fmt: skip


def _turned(hand: np.ndarray, angle: float) -> np.ndarray:
    """The hand rotation ``hand`` turned ``angle`` [rad] about its fingers' axis."""
    return Rotation.from_rotvec(hand[:, 1] * angle).as_matrix() @ hand
