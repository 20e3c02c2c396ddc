"""The drawers pulled out over an object on the table (``overhangs``: their boxes at the
sensed travel), and how a pick works under them: a rim grasp with the hand leaning away
from them (``lean``, hovering back along the leaning hand, ``lean_hover``), and a slide of
the grasped object out from under them before the lift (``slide``).

LIBERO-Goal task 3 (0 / 50): the top drawer, opened, overhangs the bowl's back, its front
10 cm above the rim. The upright hand (its palm 12.7 cm tall, robosuite's collision geoms)
came down onto the drawer's front or handle and stalled, whichever rim it took; grasped,
the bowl lifted straight up struck the drawer's bottom and fell out of the hand.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.clearance import box_clearance, footprint, overlap
from osg_control.libero.drive import GRIPPER_CLOSED
from osg_control.libero.facts import region_pose
from osg_control.libero.legs import Context, Leg
from osg_control.libero.perception import LiberoPercept

LEAN = np.radians(25.0)
"""How far a rim grasp under a drawer turns the hand about its fingers' axis, its palm
away from the drawer [rad]: the palm's top then passes outside the drawer's front on the
way down (LIBERO-Goal task 3 states 0-4, before the slide: at 15 and 20 deg one of five
picks failed, at 25 and 35 none)."""
LEAN_CLEARANCE = 0.008
"""The least gap between the upright open hand over the object and a drawer's box that
needs no lean [m]."""
SLIDE_MARGIN = 0.03
"""How far clear of the drawers' boxes a held object slides before it is lifted [m] (the
hand drifts 1-3 cm while it lifts a bowl by its rim)."""
UNDER_MARGIN = 0.01
"""How near a drawer's footprint an object's must come to count as under it [m]: the bowl
closed on 4 mm under LIBERO-Goal task 3's drawer (state 6) was 2 mm clear of it a step
later and, not slid, struck it on the lift; LIBERO-Spatial task 6's bowl, 2.3-3.5 cm beside
the cabinet's drawers, lifts clear (slid, it ran out of its 220 steps)."""
SLIDE_TOLERANCE = 0.005
"""How near clear the slide ends [m]."""


def overhangs(
    ctx: Context, percept: LiberoPercept, obj: str
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The world boxes (lower, upper) of the drawers whose box at its sensed travel lies
    wholly above ``obj``'s top."""
    top = percept.position(obj)[2] + ctx.scene.extents[obj][1][2]
    boxes = []
    for name, region in ctx.scene.regions.items():
        if region.carrier is None and region.joint is not None:
            pos, mat = region_pose(ctx.scene, percept, name)
            half = np.abs(mat) @ region.size
            if pos[2] - half[2] > top:
                boxes.append((pos - half, pos + half))
    return boxes


def lean(ctx: Context, percept: LiberoPercept, obj: str, hand: np.ndarray) -> np.ndarray:
    """``hand`` (a top-down rim grasp), turned ``LEAN`` about its fingers' axis with its
    palm's top away from the nearest drawer over ``obj`` where the upright open hand over
    ``obj`` comes within ``LEAN_CLEARANCE`` of one; else ``hand``."""
    pos = percept.position(obj)
    boxes = overhangs(ctx, percept, obj)
    if not boxes or box_clearance(pos, hand[:, 1], boxes) >= LEAN_CLEARANCE:
        return hand
    nearest = min(boxes, key=lambda b: float(np.linalg.norm(((b[0] + b[1]) / 2 - pos)[:2])))
    away = (pos - (nearest[0] + nearest[1]) / 2) * np.array([1.0, 1.0, 0.0])
    turns = [Rotation.from_rotvec(hand[:, 1] * a).as_matrix() @ hand for a in (LEAN, -LEAN)]
    return max(turns, key=lambda r: float(-r[:, 2] @ away))


def leaning(rotation: np.ndarray) -> bool:
    """Whether a grasp's ``rotation`` is not top-down (a ``lean``)."""
    return bool(rotation[2, 2] > -np.cos(LEAN / 2))


def lean_hover(point: np.ndarray, height: float, rotation: np.ndarray) -> np.ndarray:
    """The hover ``height`` above the grasp ``point`` of a leaning hand: back along its
    own axis (coming straight down, its palm swept through the drawer's front)."""
    up = -rotation[:, 2]
    return point + up * (height - point[2]) / up[2]


def under(ctx: Context, percept: LiberoPercept, obj: str) -> bool:
    """Whether ``obj``'s footprint comes within ``UNDER_MARGIN`` of a drawer's over it,
    seen from above."""
    box = footprint(ctx, percept, obj)
    return any(overlap(box, np.array([low[:2], high[:2]]), UNDER_MARGIN)
               for low, high in overhangs(ctx, percept, obj))  # fmt: skip


def out_from_under(
    ctx: Context, percept: LiberoPercept, obj: str, across: np.ndarray
) -> np.ndarray:
    """The shift along ``across`` (horizontal, either way, the shorter) that takes
    ``obj``'s footprint ``SLIDE_MARGIN`` clear of the drawers over it, box by box (zero
    when it is clear)."""
    shift = np.zeros(3)
    for low, high in overhangs(ctx, percept, obj):
        box = footprint(ctx, percept, obj) + shift[:2]
        if not overlap(box, np.array([low[:2], high[:2]]), SLIDE_MARGIN):
            continue
        lo, hi = low[:2] - SLIDE_MARGIN, high[:2] + SLIDE_MARGIN
        moves = []
        for sense in (1.0, -1.0):
            d = sense * across[:2]
            need = [((hi[k] - box[0][k]) if d[k] > 0 else (lo[k] - box[1][k])) / d[k]
                    for k in (0, 1) if abs(d[k]) > 1e-6]  # fmt: skip
            moves.append(min(need) * sense)
        shift[:2] += min(moves, key=abs) * across[:2]
    return shift


def slide(ctx: Context, obj: str) -> Leg:
    """The grasped ``obj``, where it starts ``under`` a drawer, slid along the table
    ``out_from_under`` the drawers over it, across the fingers (along them the bowl's wall
    pried the fingers open and stayed), closed on its perceived footprint (open loop, the
    hand drifted 2-3 cm); no step when it is not under one."""

    def target(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        if not under(ctx, start, obj):
            return now.tcp, None
        across = np.array([-ctx.rotation[1, 1], ctx.rotation[0, 1], 0.0])
        across /= np.linalg.norm(across)
        return now.tcp + out_from_under(ctx, now, obj, across), None

    return Leg(target, GRIPPER_CLOSED, 30, SLIDE_TOLERANCE)
