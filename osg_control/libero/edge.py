"""The pinch of an object wider than the open hand across its top edge: the hand tilted so
that one finger comes down its side and the other onto its top, closing across the edge.

No slice of such an object fits between the open fingers (``grasp.fits_hand``: LIBERO-PRO's
bigger alphabet soup can is 9.4 cm round, the Panda's pads open 7.9 cm apart), so every
top-down grasp closed on nothing above it (``libero_10_object`` tasks 0 and 7, 0 / 3 on
states 0-2). Tilted ``EDGE_TILT``, the fingers close along a line 45 deg from the side's
normal and from the top's. It is the fingers' bodies that touch the can, not their pads
(friction 1 against the pads' 2: a 45 deg cone), so the pinch holds at the edge of its
friction cones: the fingers slide toward the edge as the can's weight comes on them.
Hence the slow first lift (``EDGE_CREEP``, ``legs.creep``) and the check that the
fingers stopped ``EDGE_FIRM`` apart (``slipped``) before the rest of it. The hand comes
from outside the edge, its palm out and up; of the edges round the object turned at most
``EDGE_YAWS`` from the one facing the arm's base, the one whose tilted hand stands
clearest of the perceived neighbours, the next clearest after each failed pick. Set on
the episode's ``Context.grasps`` from the plan (``edge_grasps``), like
``tall.neck_grasps``.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.clearance import HAND_BOXES, footprint
from osg_control.libero.grasp import (
    REDECIDE,
    fingers_along,
    fits_hand,
    rim_grasped,
)
from osg_control.libero.legs import Context, GraspRule, Step, yawed
from osg_control.libero.operators import PICKS
from osg_control.libero.perception import LiberoPercept

EDGE_TILT = np.radians(45.0)
"""How far the hand is tilted from top-down about its x axis: the fingers then close 45
deg from both the side's and the top's normal [rad]."""
EDGE_DEPTH = 0.035
"""How far down the side and in from the edge on the top the fingers close [m] (at 2 cm
the can slipped out of the hand, LIBERO-PRO's ``libero_10_object`` task 0 state 0)."""
EDGE_YAWS = np.radians([0.0, 30.0, -30.0, 60.0, -60.0])
"""The turns about the vertical, from the direction of the arm's base, of the edges tried
(ties in clearance go in this order) [rad]."""
EDGE_CREEP = 0.02
"""How high the pinched object is first lifted slowly [m]: lifted at the careful pace, the
hand's first step rose 8 mm and swung 5 mm aside, and the fingers slid off the edge and
closed on nothing (a quarter of the first pinches of ``_object`` task 7)."""
EDGE_CREEP_RATE = 0.004
"""How far above the TCP the slow lift's target leads it [m] (``legs.creep``)."""
EDGE_CREEP_STEPS = 30
"""The slow lift's steps at most."""
EDGE_FIRM = 0.030
"""The least distance between the fingers of a pinch that holds [m]: the fingers slide
toward the edge as the slow lift takes the can's weight, and those that stopped nearer
than this let it fall on the way to the basket (2.5 and 2.8 cm; 3.3 cm and more on those
carried there)."""
HAND_HEIGHT = 0.04
"""How far above its lower face the hand's palm and fingers are sampled for the clearance
of a tilted hand [m]."""


def edge_grasps(ctx: Context, steps: list[Step]) -> dict[str, GraspRule]:
    """The grasps a plan's ``steps`` need: an edge pinch for each object it picks that no
    grasp of ``grasp.grips`` closes round and that is not grasped at its rim."""
    picked = {args[0] for op, args in steps if op in PICKS}
    return {obj: edge_grasp(ctx, obj) for obj in sorted(picked) if pinched(ctx, obj)}


def pinched_last(ctx: Context, steps: list[Step]) -> list[Step]:
    """``steps`` with each pinched object's carry into a region (its approach, pick, place-in
    and the retreat after it) moved after the last place-in of another object into that
    region: let go above the region, it lands on what is already there, and an object set
    down after it lands on its top (the cream cheese on the can stood with its origin 4 mm
    above the basket's region). The caller checks the new order still reaches the goal."""
    for obj in sorted({args[0] for op, args in steps if op in PICKS}):
        if not pinched(ctx, obj):
            continue
        pick = next(i for i, (op, args) in enumerate(steps)
                    if op in PICKS and args[0] == obj)  # fmt: skip
        place = next((i for i, (op, args) in enumerate(steps)
                      if i > pick and op == "place-in" and args[0] == obj), None)  # fmt: skip
        if place is None:
            continue
        region = steps[place][1][1]
        start = pick - 1 if pick and steps[pick - 1] == ("approach", (obj,)) else pick
        end = _after_retreat(steps, place)
        others = [i for i, (op, args) in enumerate(steps)
                  if i > end and op == "place-in" and args[1] == region]  # fmt: skip
        if others:
            last = _after_retreat(steps, others[-1])
            head = steps[:start] + steps[end:last]
            if head[-1][0] != "retreat":  # the hand goes home before the carry
                head.append(("retreat", (region,)))
            steps = head + steps[start:end] + steps[last:]
    return steps


def _after_retreat(steps: list[Step], place: int) -> int:
    """The index after the place at ``place`` and the retreat that follows it, if any."""
    after = place + 1
    return after + 1 if after < len(steps) and steps[after][0] == "retreat" else after


def pinched(ctx: Context, obj: str) -> bool:
    """Whether ``obj`` is taken by the edge pinch: no grasp of ``grasp.grips`` closes round
    it, it is not grasped at its rim, and it stands taller than the open hand at the pinch
    reaches below its top (``reach_below_top``: a plate, 0 / 5 pinched at LIBERO-Goal task 5
    states 0-4, would put the outer finger on the table)."""
    low, high = ctx.scene.extents[obj]
    tall = high[2] - low[2] > reach_below_top()
    return tall and not fits_hand(ctx, obj) and not rim_grasped(ctx, obj)


def reach_below_top() -> float:
    """How far below an object's top the open hand at its edge pinch reaches [m]: the TCP
    ``EDGE_DEPTH / 2`` down, the outer finger's lower corner (``HAND_BOXES``) further down
    the tilt."""
    along, _, lift = HAND_BOXES[-1]
    return float(EDGE_DEPTH / 2 + along * np.sin(EDGE_TILT) - lift * np.cos(EDGE_TILT))


def edge_grasp(ctx: Context, obj: str) -> GraspRule:
    """The edge pinch of ``obj`` (see the module docstring): decided again after a failed
    pick (the next edge, ``Context.failures``) or when the object has moved ``REDECIDE``."""
    memo: dict[str, tuple[int, np.ndarray, float]] = {}

    def rule(percept: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        tries, pos = ctx.failures.get(obj, 0), percept.position(obj)
        last = memo.get(obj)
        if last is None or last[0] != tries or np.linalg.norm(last[1] - pos) >= REDECIDE:
            memo[obj] = (tries, pos.copy(), _choose(ctx, percept, obj, tries))
        return _pose(ctx, percept, obj, memo[obj][2])

    return rule


def _choose(ctx: Context, percept: LiberoPercept, obj: str, tries: int) -> float:
    """The turn of the edge taken: of ``EDGE_YAWS``, the one whose hand stands clearest of
    the neighbours (ties in their order); the ``tries``-th on. (The first of them 8 mm
    clear, the base's side first, slid LIBERO-PRO ``_object`` task 7's can 5 cm along the
    table as the fingers closed and held nothing: 1 / 10 on states 0-9.)"""
    gaps = [(_clearance(ctx, percept, obj, *_pose(ctx, percept, obj, y)), y) for y in EDGE_YAWS]
    order = [y for gap, y in sorted(gaps, key=lambda g: -g[0])]
    return float(order[tries % len(order)])


def _pose(
    ctx: Context, percept: LiberoPercept, obj: str, yaw: float
) -> tuple[np.ndarray, np.ndarray]:
    """The TCP and rotation of the pinch at the edge turned ``yaw`` from the base's side."""
    pos, rot = percept.objects[obj]
    corners = np.array([pos + rot @ c for lo, hi in ctx.scene.parts[obj]
                        for c in (np.r_[lo[:2], 0.0], np.r_[hi[:2], 0.0],
                                  np.r_[lo[0], hi[1], 0.0], np.r_[hi[0], lo[1], 0.0])])  # fmt: skip
    centre = (corners.min(axis=0) + corners.max(axis=0)) / 2
    out = (ctx.base_xy - centre) * np.array([1.0, 1.0, 0.0])
    out = yawed(yaw) @ (out / np.linalg.norm(out))
    radius = float(np.max((corners - centre) @ out))
    top = pos[2] + ctx.scene.extents[obj][1][2]
    edge = np.r_[centre[:2], top] + radius * out
    tcp = edge - EDGE_DEPTH / 2 * (out + np.array([0.0, 0.0, 1.0]))
    level = fingers_along(ctx, out)
    tilts = [Rotation.from_rotvec(level[:, 0] * a).as_matrix() @ level
             for a in (EDGE_TILT, -EDGE_TILT)]  # fmt: skip
    return tcp, max(tilts, key=lambda r: float(r[:, 2] @ -out))  # the palm out and up


def _clearance(
    ctx: Context, percept: LiberoPercept, obj: str, tcp: np.ndarray, rotation: np.ndarray
) -> float:
    """The least horizontal gap between the tilted open hand (``HAND_BOXES``, sampled up
    to ``HAND_HEIGHT`` above their lower faces) and the footprint of every object other
    than ``obj`` where the hand is below that object's top (negative: inside it)."""
    points = np.array([tcp + rotation @ np.array([x * across, y * along, -lift - t])
                       for along, across, lift in HAND_BOXES
                       for x in (-1.0, 0.0, 1.0) for y in np.linspace(-1.0, 1.0, 5)
                       for t in (0.0, HAND_HEIGHT / 2, HAND_HEIGHT)])  # fmt: skip
    least = np.inf
    for other in percept.objects:
        if other == obj:
            continue
        box = footprint(ctx, percept, other)
        below = points[points[:, 2] < percept.position(other)[2] + ctx.scene.extents[other][1][2]]
        for p in below[:, :2]:
            outside = np.maximum(box[0] - p, p - box[1])
            gap = np.linalg.norm(np.maximum(outside, 0.0)) if np.any(outside > 0) else outside.max()
            least = min(least, float(gap))
    return least


def slipped(percept: LiberoPercept) -> bool:
    """Whether a pinch's fingers slid too near the edge to hold (``EDGE_FIRM``): the pick
    then ends low, fails, and lets go there (the retry takes the next edge)."""
    return percept.finger_width < EDGE_FIRM
