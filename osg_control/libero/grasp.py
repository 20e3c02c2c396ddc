"""Where and how the hand grasps an object from above: the grasp point in the object's
frame (``grips``: across its narrower side, or a slice of it that fits the open hand; the
one taken, ``chosen_grip``, keeps the open hand clear of the perceived neighbours and
changes after a failed pick; or a bowl's or mug's rim) and the top-down rotation turned
about the vertical to match (``grasp_rotation``, ``fingers_along``), all from the percept
and the scene's geometry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.clearance import HAND_BOXES, fixture_clearance, hand_clearance
from osg_control.libero.facts import holds
from osg_control.libero.legs import TURN_TOLERANCE, Context, yawed
from osg_control.libero.overhang import lean
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.problem import Atom

TURN_WINDOW = (np.radians(15.0), np.radians(25.0))
"""How far past a quarter turn from the start a grasp may turn the hand about the vertical,
clockwise and counter-clockwise seen from above [rad]. The Panda's last joint starts at
0.76 rad and a counter-clockwise turn runs it down toward its limit at -2.90 (3.7 rad
away), a clockwise one up toward 2.90 (2.1 rad away): counter-clockwise has the room.
(At 15 deg both ways, the rim grasp of LIBERO-10 task 4's second mug, 105.4 deg
counter-clockwise, was refused for the one 150 deg round from the first mug's, and the
hand drifted 40 cm while it turned: states 14, 22, 32, 36.)"""
RIM_GRASP = ("bowl", "mug", "plate")
"""Object categories grasped at the rim (their origin is inside them, or they are wider
than the open hand: a plate, 13.8 cm across, closed on at its centre every time,
LIBERO-Goal task 5)."""
RIM_INSET = 0.012
"""How far inside the rim's outer radius the TCP closes [m] (but in a drawer:
``_rim_inset``)."""
ROUND = 1.3
"""An object whose horizontal sides differ by less than this ratio is grasped unturned."""
GRASP_ABOVE_ORIGIN = 0.005
"""The grasp height above an object's origin tried first [m] (2 cm higher missed the flat
boxes: cream cheese, butter, pudding)."""
GRASP_FLOOR = 0.03
"""The least height above an object's bottom the TCP closes at, up to half the object's
height [m]: an object whose origin is at its bottom (the wine bottle) was grasped at the
table, the fingertips on it."""
GRIP_WIDTH = 0.07
"""The widest side the open hand (about 8 cm) closes round with a margin [m]."""
BAND = 0.02
"""The least height of an object's part the fingertips close on [m]."""
FINGER_HALF = 0.012
"""Half the width of a finger across its sliding direction [m]."""
GRIP_STEP = 0.005
"""The spacing of the slices ``grip`` tries [m]."""
RIM_DEPTH = 0.02
"""How far below a rim the fingertips close [m]: at most down to ``RIM_FLOOR`` above the
object's bottom (a plate's rim stands 1.9 cm)."""
RIM_FLOOR = 0.005
"""The least height of the open fingers' lower faces (``clearance.HAND_BOXES``) above
the object's bottom at a rim grasp [m]: they stay off the table."""
GRASP_CLEARANCE = 0.008
"""The least gap between the hand at a grasp and a neighbour's footprint [m]."""
RETRY_SHIFT = 0.015
"""How far a retried grasp's point lies from the ones tried before, on the same axis [m]."""
REDECIDE = 0.02
"""How far an object must move before its grasp is chosen again [m]."""
TOP_RISE = 0.015
"""The least height a part must stand above the rest of an object for the fingers to
close on it from above with their lower faces over the rest (``HAND_BOXES``: 1.2 cm below
the TCP; the pads reach 4 mm below it) [m]: a moka pot's lid knob stands 1.9 cm up."""
TOP_GAP = 0.003
"""How far the fingers' lower faces keep above the rest of the object at a top grasp [m]."""


def _yaw(rotation: np.ndarray, angle: float) -> np.ndarray:
    return yawed(angle) @ rotation


@dataclass(frozen=True)
class Grip:
    """Where the fingers close on an object, in its own frame: the TCP point, and the
    object axis (0: x, 1: y) they slide along (None: as the hand comes, a round object)."""

    point: np.ndarray
    axis: int | None


def slab(ctx: Context, obj: str, axis: int, centre: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The object's geoms a finger pair sliding along ``axis`` sweeps down through when
    centred at ``centre`` on the other horizontal axis."""
    other = 1 - axis
    return [(lo, hi) for lo, hi in ctx.scene.parts[obj]
            if lo[other] < centre + FINGER_HALF and hi[other] > centre - FINGER_HALF]  # fmt: skip


def grips(ctx: Context, obj: str) -> list[Grip]:
    """Every way to grasp ``obj`` from above, the preferred first: just above its origin
    (at least ``GRASP_FLOOR`` above its bottom) across its narrower side when everything
    the fingers pass on the way down fits between them (``GRIP_WIDTH``); then each slice of
    the object, along either horizontal axis, that fits, the narrowest and most central
    first (a moka pot's handle), at the origin's height clamped into that slice. A round
    object has one: unturned, above its origin."""
    low, high = ctx.scene.extents[obj]
    width = high[:2] - low[:2]
    axis = int(np.argmin(width))
    lift = min(low[2] + GRASP_FLOOR, (low[2] + high[2]) / 2)  # an origin at the bottom
    default = np.array([0.0, 0.0, max(GRASP_ABOVE_ORIGIN, lift)])
    if max(width) < ROUND * min(width) and min(width) <= GRIP_WIDTH:
        return [Grip(default, None)]
    candidates: list[tuple[float, int, Grip]] = []
    if not _fits(slab(ctx, obj, axis, 0.0), axis):  # wider than the hand at its centre
        for a in (axis, 1 - axis):
            top = _top_grip(slab(ctx, obj, a, 0.0), a)
            if top is not None:
                candidates.append((-np.inf, len(candidates), top))
    for a in (axis, 1 - axis):
        for centre in np.arange(low[1 - a], high[1 - a] + 1e-9, GRIP_STEP):
            boxes = slab(ctx, obj, a, float(centre))
            if not _fits(boxes, a):
                continue
            lo_a, hi_a = _span(boxes, a)
            top, bottom = max(b[1][2] for b in boxes), min(b[0][2] for b in boxes)
            point = np.zeros(3)
            point[a], point[1 - a] = (lo_a + hi_a) / 2, centre
            point[2] = max(bottom + BAND / 2, min(GRASP_ABOVE_ORIGIN, top - BAND / 2))
            central = a == axis and abs(centre) < GRIP_STEP / 2 + 1e-9
            cost = -np.inf if central else hi_a - lo_a + abs(centre) * 0.1
            candidates.append((cost, len(candidates), Grip(point, a)))
    if not candidates:
        return [Grip(default, axis)]
    return [g for _, _, g in sorted(candidates, key=lambda c: c[:2])]


def fits_hand(ctx: Context, obj: str) -> bool:
    """Whether some slice of ``obj`` fits between the open fingers (``GRIP_WIDTH``) along
    either horizontal axis: a grasp of ``grips`` closes round it."""
    low, high = ctx.scene.extents[obj]
    return any(_fits(slab(ctx, obj, a, float(c)), a) for a in (0, 1)
               for c in np.arange(low[1 - a], high[1 - a] + 1e-9, GRIP_STEP))  # fmt: skip


def _span(boxes: list[tuple[np.ndarray, np.ndarray]], axis: int) -> tuple[float, float]:
    """The lowest and highest extent of ``boxes`` along ``axis``."""
    return min(b[0][axis] for b in boxes), max(b[1][axis] for b in boxes)


def _fits(boxes: list[tuple[np.ndarray, np.ndarray]], axis: int) -> bool:
    """Whether a slab's ``boxes`` fit between the open fingers along ``axis``."""
    if not boxes:
        return False
    low, high = _span(boxes, axis)
    return high - low <= GRIP_WIDTH


def _top_grip(boxes: list[tuple[np.ndarray, np.ndarray]], axis: int) -> Grip | None:
    """A grasp over the object's centre on the part of a slab that stands ``TOP_RISE``
    above the rest of it and fits the open hand (a moka pot's lid knob: carried by its
    handle, the pot hung 35-57 deg tilted and fell over when set down; hung from above its
    centre it hangs level), the fingers' lower faces ``TOP_GAP`` over the rest; None when
    no part stands so."""
    top = max((b[1][2] for b in boxes), default=-np.inf)
    for level in sorted({float(b[1][2]) for b in boxes if b[1][2] < top}, reverse=True):
        upper = [b for b in boxes if b[1][2] > level]
        if top - level < TOP_RISE or not _fits(upper, axis):
            continue
        point = np.zeros(3)
        point[axis] = sum(_span(upper, axis)) / 2
        point[2] = level - HAND_BOXES[-1][2] + TOP_GAP
        return Grip(point, axis)
    return None


def grip(ctx: Context, obj: str) -> Grip:
    """The preferred grasp of ``obj`` from its geometry alone (``grips``' first)."""
    return grips(ctx, obj)[0]


def _finger_axis(ctx: Context, percept: LiberoPercept, obj: str, g: Grip) -> np.ndarray:
    """The world direction the fingers slide along for grasp ``g``."""
    return ctx.base[:, 1] if g.axis is None else percept.objects[obj][1][:, g.axis]


def chosen_grip(ctx: Context, percept: LiberoPercept, obj: str) -> Grip:
    """The grasp the hand takes: the first of ``grips`` whose hand stands
    ``GRASP_CLEARANCE`` clear of the perceived neighbours (``clearance.hand_clearance``),
    else the preferred one (a slice at the object's end, taken for being the clearest,
    tipped a standing book over); each failed pick of ``obj`` (``Context.failures``) moves
    on to the next grasp that differs (another axis, or ``RETRY_SHIFT`` along the object).
    Decided once per attempt, again only when the object has moved ``REDECIDE``."""
    tries = ctx.failures.get(obj, 0)
    pos, rot = percept.objects[obj]
    memo = ctx.grips.get(obj)
    if memo is not None and memo[0] == tries and np.linalg.norm(memo[1] - pos) < REDECIDE:
        return memo[2]
    scored = []
    for g in grips(ctx, obj):
        tcp = pos + rot @ g.point
        gap = hand_clearance(ctx, percept, tcp, _finger_axis(ctx, percept, obj, g), obj)
        scored.append((gap, g))
    clear = [g for gap, g in scored if gap >= GRASP_CLEARANCE]
    rest = [g for gap, g in sorted(scored, key=lambda s: -s[0]) if gap < GRASP_CLEARANCE]
    if not clear:  # the preferred grasp first all the same, then the clearest
        rest.sort(key=lambda g: g is not scored[0][1])
    distinct: list[Grip] = []
    for g in clear + rest:
        if all(g.axis != k.axis or np.linalg.norm(g.point[:2] - k.point[:2]) >= RETRY_SHIFT
               for k in distinct):  # fmt: skip
            distinct.append(g)
    chosen = distinct[tries % len(distinct)]
    ctx.grips[obj] = (tries, pos.copy(), chosen)
    return chosen


def grasp_rotation(ctx: Context, percept: LiberoPercept, obj: str) -> np.ndarray:
    """The top-down grasp turned about the vertical so that the fingers close across the
    side ``grip`` chose (unturned for a round object); the plan's own grasp where it set
    one (``Context.grasps``)."""
    if obj in ctx.grasps:
        return ctx.grasps[obj](percept)[1]
    if rim_grasped(ctx, obj):
        return _rim_rotation(ctx, percept, obj)
    g = chosen_grip(ctx, percept, obj)
    if g.axis is None:
        return ctx.base
    return fingers_along(ctx, _finger_axis(ctx, percept, obj, g))


def _rim_rotation(ctx: Context, percept: LiberoPercept, obj: str) -> np.ndarray:
    """A rim grasp's hand: its long side across the reach (the fingers along it) when
    ``obj`` is perceived in a drawer or the goal puts it into one (the hand then fits under
    the cabinet's top: turned the other way it stalled 3 cm above a bowl in the top drawer,
    LIBERO-Spatial task 4, 0 / 50; leaning away from a drawer over it, ``overhang.lean``),
    else
    whichever of that and the fingers across the reach turns the hand less from the start:
    turning a bowl's grasp a quarter turn in place took the approach's 90 steps, and the
    pick repeated it (LIBERO-Goal tasks 1, 4, 8, the bowl, out of their 300 steps); the
    other where only its rims are in the arm's reach (``_reached``: a bowl 0.8 m out,
    LIBERO-Spatial task 6, whose rims across the reach lie 1-1.5 cm beyond it)."""
    reach = percept.position(obj) - ctx.base_xy
    along = fingers_along(ctx, reach)
    into = any(a.predicate == "in" and a.args[0] == obj and a.args[1] in _drawers(ctx)
               for a in ctx.goal)  # fmt: skip
    if into or _in_drawer(ctx, percept, obj):
        return lean(ctx, percept, obj, along)
    across = fingers_along(ctx, np.array([-reach[1], reach[0], 0.0]))
    first, other = sorted((along, across), key=lambda r: abs(turned_from_start(ctx, r)))

    def reached(rotation: np.ndarray) -> bool:
        return any(
            _reached(ctx, percept, obj, p, rotation) for p in _rims(ctx, percept, obj, rotation)
        )

    return other if not reached(first) and reached(other) else first


def _drawers(ctx: Context) -> set[str]:
    """The scene's drawer regions (a region on a joint)."""
    return {r for r, box in ctx.scene.regions.items() if box.joint is not None}


def _in_drawer(ctx: Context, percept: LiberoPercept, obj: str) -> bool:
    """Whether ``obj`` has been perceived in a drawer since it last moved ``REDECIDE``: the
    drawer's sensed travel is noisy, and a bowl near its region's edge was seen in and out
    of it by turns, the grasp's hand turning back and forth between the two rules
    (LIBERO-Spatial task 4 state 0: the approach's 90 steps in place)."""
    pos = percept.position(obj)
    since = ctx.drawered.get(obj)
    if since is None or np.linalg.norm(pos - since[0]) > REDECIDE:
        since = (pos.copy(), False)
    seen = any(holds(ctx.scene, percept, Atom("in", (obj, r))) for r in _drawers(ctx))
    ctx.drawered[obj] = (since[0], since[1] or seen)
    return ctx.drawered[obj][1]


def _rim_inset(ctx: Context, percept: LiberoPercept, obj: str) -> float:
    """How far inside the rim's outer radius the TCP closes on ``obj`` [m]:
    ``RIM_INSET``, but in a drawer, whose front wall stands about a finger beyond a bowl's
    rim, so far that the outer open finger comes down just outside the rim (half the open
    span less a finger's half-width): at ``RIM_INSET`` it landed on the wall's top and the
    pick failed (LIBERO-Spatial task 4, 7 of 50)."""
    if _in_drawer(ctx, percept, obj):
        return ctx.open_span / 2 - FINGER_HALF
    return RIM_INSET


def in_turn_window(angle: float) -> bool:
    """Whether a turn of the hand by ``angle`` about the vertical from the start's
    (counter-clockwise seen from above, positive) is within ``TURN_WINDOW``."""
    clockwise, counter = TURN_WINDOW
    return -np.pi / 2 - clockwise <= angle <= np.pi / 2 + counter


def turned_from_start(ctx: Context, rotation: np.ndarray) -> float:
    """The angle a top-down ``rotation`` is turned about the vertical from the start's
    (``Context.base``), counter-clockwise seen from above positive [rad]."""
    return float(Rotation.from_matrix(rotation @ ctx.base.T).as_rotvec()[2])


def fingers_along(ctx: Context, direction: np.ndarray) -> np.ndarray:
    """The top-down rotation turned about the vertical so that the fingers slide along
    ``direction``'s horizontal part, by at most a quarter turn (and ``TURN_WINDOW``) from
    the start's: the wrist keeps clear of its limits. Where both turns are in that window
    (the fingers are alike), the one nearer the last commanded rotation: a direction near
    the boundary would otherwise flip the wrist by half a turn between steps."""
    finger = ctx.base[:, 1]
    angle = float(np.arctan2(finger[0] * direction[1] - finger[1] * direction[0],
                             finger[:2] @ direction[:2]))  # fmt: skip
    turns = [_yaw(ctx.base, a) for a in (angle, angle - np.pi, angle + np.pi)
             if in_turn_window(a)]  # fmt: skip
    return max(turns, key=lambda r: float(np.trace(r.T @ ctx.rotation)))


def rim_grasped(ctx: Context, obj: str) -> bool:
    """Whether ``obj`` is grasped at its rim (``RIM_GRASP``)."""
    return any(word in ctx.categories.get(obj, "") for word in RIM_GRASP)


def grasp_point(ctx: Context, percept: LiberoPercept, obj: str) -> np.ndarray:
    """Where the TCP closes on ``obj``: just above its origin, or on a bowl's, mug's or
    plate's rim (on the side away from a handle: the side of the rim further from the box's
    centre, unless only the other is in the arm's reach, ``_reached``; a rim too low for
    ``RIM_DEPTH``, a plate's, on the side where the open hand, its palm then low, stands
    clearest of the objects and the fixtures' boxes, then the nearer the arm's base: on the
    cabinet's side its long side reached under the cabinet's front and stalled, LIBERO-Goal
    task 5); the plan's own grasp where it set one (``Context.grasps``)."""
    if obj in ctx.grasps:
        return ctx.grasps[obj](percept)[0]
    pos, rot = percept.objects[obj]
    low, high = ctx.scene.extents[obj]
    if not rim_grasped(ctx, obj):
        return pos + rot @ chosen_grip(ctx, percept, obj).point
    rotation = grasp_rotation(ctx, percept, obj)
    axis = rotation[:, 1] * np.array([1.0, 1.0, 0.0])
    axis /= np.linalg.norm(axis)
    centre = pos + rot @ ((low + high) / 2)
    rims = _rims(ctx, percept, obj, rotation)
    if _low_rim(ctx, obj):  # the side the open hand stands clearest at, then the nearer

        def room(p: np.ndarray) -> tuple[float, float]:
            gap = min(hand_clearance(ctx, percept, p, axis, obj),
                      fixture_clearance(ctx, percept, p, axis))  # fmt: skip
            return min(gap, GRASP_CLEARANCE), -float(np.linalg.norm((p - ctx.base_xy)[:2]))

        return max(rims, key=room)
    return max(rims, key=lambda p: (_reached(ctx, percept, obj, p, rotation),
                                    float(np.linalg.norm((p - centre)[:2]))))  # fmt: skip


def _rims(ctx: Context, percept: LiberoPercept, obj: str, rotation: np.ndarray) -> list[np.ndarray]:
    """The two points a rim grasp with ``rotation`` closes at: either side of ``obj``'s
    origin along the fingers, ``_rim_inset`` in from its radius, ``RIM_DEPTH`` below its
    top (at least ``_rim_floor`` above its origin)."""
    pos, _ = percept.objects[obj]
    low, high = ctx.scene.extents[obj]
    axis = rotation[:, 1] * np.array([1.0, 1.0, 0.0])
    axis /= np.linalg.norm(axis)
    radius = float(min(np.abs(low[:2]).min(), np.abs(high[:2]).min()))
    radius -= _rim_inset(ctx, percept, obj)
    height = max(pos[2] + high[2] - RIM_DEPTH, pos[2] + _rim_floor(ctx, obj))
    return [np.r_[(pos + side * radius * axis)[:2], height] for side in (1.0, -1.0)]


def _reached(
    ctx: Context, percept: LiberoPercept, obj: str, point: np.ndarray, rotation: np.ndarray
) -> bool:
    """Whether the arm reaches the grasp of ``obj`` at ``point`` with ``rotation`` from
    the perceived joints (``drive.JointTargetDriver.reaches``): checked once per attempt
    and grasp, again when ``obj`` has moved ``REDECIDE`` (the arm moves on meanwhile)."""
    tries, pos = ctx.failures.get(obj, 0), percept.position(obj)
    memo = ctx.reach_checks.get(obj)
    if memo is None or memo[0] != tries or np.linalg.norm(memo[1] - pos) >= REDECIDE:
        memo = ctx.reach_checks[obj] = (tries, pos.copy(), {})
    key = tuple(round(float(v), 3) for v in np.r_[point - pos, rotation.ravel()])
    if key not in memo[2]:
        memo[2][key] = ctx.driver.reaches(percept.joints, point, rotation, TURN_TOLERANCE)
    return memo[2][key]


def carry_point(ctx: Context, percept: LiberoPercept, obj: str) -> np.ndarray:
    """The point of ``obj`` a held object is carried above (``pick_place.approach``): its
    grasp point, save for a low rim's (a plate's), where the held object goes over its
    middle."""
    if not _low_rim(ctx, obj):
        return grasp_point(ctx, percept, obj)
    pos, rot = percept.objects[obj]
    return pos + rot @ chosen_grip(ctx, percept, obj).point


def _rim_floor(ctx: Context, obj: str) -> float:
    """The lowest a rim grasp's TCP goes above ``obj``'s origin: the open fingers' lower
    faces (``clearance.HAND_BOXES``) ``RIM_FLOOR`` above its bottom."""
    return float(ctx.scene.extents[obj][0][2]) + RIM_FLOOR - HAND_BOXES[1][2]


def _low_rim(ctx: Context, obj: str) -> bool:
    """Whether ``obj`` is grasped at a rim too low for ``RIM_DEPTH`` (a plate's)."""
    return rim_grasped(ctx, obj) and ctx.scene.extents[obj][1][2] - RIM_DEPTH < _rim_floor(ctx, obj)
