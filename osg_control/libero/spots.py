"""Where a held object is set down: over an object's top, a region's floor, or a spot of
a region's top that leaves room for what the goal still puts there (``surface``); and,
where that spot lies beyond the arm's reach, the region's reachable spot, the object turned
a quarter turn where that makes room (``set_down``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from osg_control.libero.clearance import HAND_BOXES, carried, footprint
from osg_control.libero.drive import REACH_CHECK_STEPS
from osg_control.libero.edge import pinched
from osg_control.libero.facts import holds, region_pose, room
from osg_control.libero.grasp import fingers_along
from osg_control.libero.lay import across, lay, lies_down
from osg_control.libero.legs import TURN_TOLERANCE, Context, yawed
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.rest import lowest_rest, too_wide

DROP = 0.02
"""Height of the held object's bottom above the surface when released [m]."""
CLEARANCE = 0.02
"""The gap between footprints a place on a region's top keeps where it can [m]."""
EDGE_MARGIN = 0.01
"""How far inside a region's footprint an object is set down at most [m]."""
TURNS = (0.0, np.pi / 2, -np.pi / 2)
"""The turns about the vertical a set-down out of reach may give the held object [rad]."""


def surface(
    ctx: Context, percept: LiberoPercept, target: str, inside: bool, held_obj: str
) -> np.ndarray:
    """The point the held object ``held_obj`` is set down over: an object's top centre, a
    region's floor centre (``in``; its box's top for an object pinched at its edge,
    ``edge``: the tilted hand reaches past its side and caught a basket's wall, the object
    wedged in it; in a drawer, the middle of its ``facts.room`` along its pull: the part
    under the cabinet's front or the handles above is not reached from above), or on a
    region's top its place in the row it shares with what the goal still puts there
    (``_row_spot``), else a free spot (``_free_spot``)."""
    if target in percept.objects:
        pos, _ = percept.objects[target]
        return pos + np.array([0.0, 0.0, ctx.scene.extents[target][1][2]])
    if inside and not pinched(ctx, held_obj) and too_wide(ctx, percept, held_obj, target):
        resting = lowest_rest(ctx, percept, held_obj, target)
        if resting is not None:
            return resting
    pos, mat = region_pose(ctx.scene, percept, target)
    half = np.abs(mat @ ctx.scene.regions[target].size)
    if not inside:
        coming = _still_to_come(ctx, percept, target, held_obj)
        spot = (_row_spot(ctx, percept, pos, held_obj, coming) if coming else
                _free_spot(ctx, percept, pos, half[:2], held_obj))  # fmt: skip
        pos = np.r_[spot[:2], pos[2]]
    elif ctx.scene.regions[target].joint is not None:
        joint = ctx.scene.joints[str(ctx.scene.regions[target].joint)]
        out = joint.outward
        pos = pos + out * (sum(room(ctx.scene, percept, target)) / 2 - pos @ out)
        if lies_down(ctx, held_obj, target):
            pos = lay(ctx, percept, held_obj, target).stand
    floor = inside and not pinched(ctx, held_obj)
    return pos + np.array([0.0, 0.0, -half[2] if floor else half[2]])


def _still_to_come(ctx: Context, percept: LiberoPercept, target: str, held_obj: str) -> list[str]:
    """The other objects the goal puts on ``target`` that are not perceived there yet."""
    return [a.args[0] for a in ctx.goal
            if a.predicate == "on" and a.args[1] == target and a.args[0] != held_obj
            and a.args[0] in percept.objects and not holds(ctx.scene, percept, a)]  # fmt: skip


def _gap(a: np.ndarray, b: np.ndarray) -> float:
    """How far apart two xy boxes (lower, upper) are along the axis that parts them most
    (negative: they overlap)."""
    return float(np.max(np.maximum(a[0] - b[1], b[0] - a[1])))


def _row_spot(
    ctx: Context, percept: LiberoPercept, centre: np.ndarray, held_obj: str, coming: list[str]
) -> np.ndarray:
    """Where on a region's top to set ``held_obj`` down when the goal puts ``coming`` there
    after it: their footprints (about their origins, at their perceived yaw) in a row
    ``CLEARANCE`` apart along the axis they leave most room along, centred on the
    region's centre, ``held_obj`` at the end of the row that stands clearest of the other
    objects (up to ``CLEARANCE``), then the farther from the arm's base (two moka pots on
    one stove: the first set down at its centre left the second no room)."""
    boxes = [footprint(ctx, percept, o) - percept.position(o)[:2] for o in [held_obj, *coming]]
    axis = int(np.argmin([sum(float(b[1][k] - b[0][k]) for b in boxes) for k in (0, 1)]))
    row = sum(float(b[1][axis] - b[0][axis]) for b in boxes) + CLEARANCE * len(coming)
    own = boxes[0]
    ends = []
    for side, edge in ((1.0, own[1][axis]), (-1.0, own[0][axis])):
        spot = np.array(centre[:2], dtype=float)
        spot[axis] += side * row / 2 - edge
        ends.append(spot)
    others = [footprint(ctx, percept, o) for o in percept.objects if o != held_obj]

    def rank(spot: np.ndarray) -> tuple[float, float]:
        gaps = [_gap(o, own + spot) for o in others]
        return min([CLEARANCE, *gaps]), float(np.linalg.norm(spot - ctx.base_xy[:2]))

    return max(ends, key=rank)


def _free_spot(
    ctx: Context, percept: LiberoPercept, centre: np.ndarray, half: np.ndarray, held_obj: str
) -> np.ndarray:
    """Where on a region's top to set ``held_obj`` down: its centre when it would stand
    ``CLEARANCE`` clear of every other object's footprint there, else the point of the
    region's footprint (less ``EDGE_MARGIN``) whose footprint stands clearest of them and
    of the hand turning a knob the goal still turns (``_knob_sweeps``; off the centre it
    can crowd the knob) (up to ``CLEARANCE``), the nearest the centre among equals (the
    second moka pot on a stove)."""
    own = footprint(ctx, percept, held_obj) - percept.position(held_obj)[:2]
    others = [footprint(ctx, percept, o) for o in percept.objects if o != held_obj]

    def clearance(spot: np.ndarray) -> float:
        return min([CLEARANCE, *(_gap(o, own + spot) for o in others)])

    if clearance(centre[:2]) >= CLEARANCE:
        return centre
    others += _knob_sweeps(ctx, percept)
    best = max(
        _grid(centre, half), key=lambda s: (clearance(s), -float(np.linalg.norm(s - centre[:2])))
    )
    return np.r_[best, centre[2]]


def _grid(centre: np.ndarray, half: np.ndarray) -> list[np.ndarray]:
    """The spots a region's top is searched over: 9 x 9 points of its footprint (centred on
    ``centre``, half-sizes ``half``) less ``EDGE_MARGIN`` (xy)."""
    reach = np.maximum(half - EDGE_MARGIN, 0.0)
    grid = np.linspace(-1.0, 1.0, 9)
    return [centre[:2] + reach * (a, b) for a in grid for b in grid]


def _knob_sweeps(ctx: Context, percept: LiberoPercept) -> list[np.ndarray]:
    """The xy boxes the turning hand sweeps at each knob the goal still turns: the palm's
    half-length (``clearance.HAND_BOXES``) round the knob's grip point (a moka pot set
    down beside a frying pan's handle, next to the knob, was pushed off by the turn)."""
    reach = HAND_BOXES[0][0]
    pending = [a.args[0] for a in ctx.goal if a.predicate in ("turnon", "turnoff")
               and a.args[0] in ctx.scene.knobs and not holds(ctx.scene, percept, a)]  # fmt: skip
    return [ctx.scene.knobs[f][:2] + np.array([[-reach], [reach]]) for f in pending]


@dataclass(frozen=True)
class SetDown:
    """Where a held object is set down: the surface ``point`` it goes down over; for a spot
    moved into the arm's reach (``set_down``), the hand ``turned`` about the vertical
    (None: not turned) from the hand ``before`` it, and the point at the carrying height
    the arm gets nearest the spot (``over``; None: the spot at the carrying height)."""

    point: np.ndarray
    turned: np.ndarray | None = None
    before: np.ndarray | None = None
    over: np.ndarray | None = None


def set_down(
    ctx: Context, percept: LiberoPercept, target: str, inside: bool, held_obj: str
) -> SetDown:
    """Where ``held_obj`` is set down: over ``surface``'s point, the hand turned with its
    fingers across the drawer's pull for an object laid down in it (``lay``: along it,
    the 21 cm palm met the cabinet's front above the drawer and held the object up);
    unless that is a region's top beyond the arm's reach (``reaches``); then at the best
    spot the arm reaches (``_spot_in_reach``), the object turned a quarter turn where that
    makes room, the hand coming over it at the carrying height as near as it gets (the
    reach shrinks with height: there it stopped 2 cm short and waited out its steps).
    LIBERO-PRO's swapped kitchen (``libero_10_swap`` task 8) puts the stove's cook region
    0.87 m out: the top-down hand reaches its near 3 cm, where two moka pots stand side by
    side only with one turned."""
    point = surface(ctx, percept, target, inside, held_obj)
    if inside and lies_down(ctx, held_obj, target):  # the palm kept off the cabinet's front
        return SetDown(point, fingers_along(ctx, across(ctx, target)), ctx.rotation)
    if inside or target in percept.objects or reaches(ctx, percept, held_obj, point, 0.0):
        return SetDown(point)
    pos, mat = region_pose(ctx.scene, percept, target)
    half = np.abs(mat @ ctx.scene.regions[target].size)[:2]
    coming = _still_to_come(ctx, percept, target, held_obj)
    found = _spot_in_reach(ctx, percept, held_obj, point, half, pos, coming)
    if found is None:
        return SetDown(point)
    spot, turn = found
    hand = yawed(turn) @ ctx.rotation
    goal = _hand_at(ctx, percept, held_obj, spot, turn)
    goal[2] = max(goal[2], percept.tcp[2])
    over = ctx.driver.settle(percept.joints, goal, hand, REACH_CHECK_STEPS)[0]
    return SetDown(spot, hand if turn else None, ctx.rotation if turn else None, over)


def _hand_at(
    ctx: Context, percept: LiberoPercept, held_obj: str, point: np.ndarray, turn: float
) -> np.ndarray:
    """The TCP that sets ``held_obj``, turned by ``turn``, down over ``point``: its bottom
    ``DROP`` above it."""
    lift = np.array([0.0, 0.0, DROP - ctx.scene.extents[held_obj][0][2]])
    return point + lift + yawed(turn) @ carried(percept, held_obj)


def reaches(
    ctx: Context, percept: LiberoPercept, held_obj: str, point: np.ndarray, turn: float
) -> bool:
    """Whether the IK, iterated from the perceived joints, brings the hand holding
    ``held_obj`` (turned by ``turn``) to set it down over ``point``: within
    ``drive.REACH_TOLERANCE`` and ``TURN_TOLERANCE`` of the hand's pose there."""
    rotation = yawed(turn) @ ctx.rotation
    hand = _hand_at(ctx, percept, held_obj, point, turn)
    return ctx.driver.reaches(percept.joints, hand, rotation, TURN_TOLERANCE)


def _spot_in_reach(
    ctx: Context, percept: LiberoPercept, held_obj: str, first: np.ndarray, half: np.ndarray,
    centre: np.ndarray, coming: list[str],
) -> tuple[np.ndarray, float] | None:  # fmt: skip
    """The region's grid point (its footprint less ``EDGE_MARGIN``) and turn (``TURNS``;
    the hand kept within ``grasp.TURN_WINDOW`` of the start's: turned past it, the wrist
    did not come back to grasp the second pot) the arm reaches to set ``held_obj`` down
    at, whose footprint stands clearest of the other objects' and of the knobs' sweeps (up
    to ``CLEARANCE``), that leaves each of ``coming`` a reachable spot ``CLEARANCE`` clear
    of it and of the others, the nearest ``first`` among equals; None where the arm
    reaches none."""
    spots = [np.r_[xy, first[2]] for xy in _grid(centre, half)]
    standing = {o: footprint(ctx, percept, o) for o in percept.objects if o != held_obj}
    sweeps = _knob_sweeps(ctx, percept)
    others = [*standing.values(), *sweeps]
    turns = range(len(TURNS))
    memo: dict[tuple[int, int], bool] = {}

    def reached(i: int, k: int) -> bool:
        if (i, k) not in memo:
            memo[i, k] = reaches(ctx, percept, held_obj, spots[i], TURNS[k])
        return memo[i, k]

    def box(obj: str, i: int, k: int) -> np.ndarray:
        return footprint(ctx, percept, obj, TURNS[k]) - percept.position(obj)[:2] + spots[i][:2]

    def clearance(placed: np.ndarray, among: list[np.ndarray]) -> float:
        return min([CLEARANCE, *(_gap(o, placed) for o in among)])

    def room_for(obj: str, placed: np.ndarray) -> bool:
        among = [*(b for o, b in standing.items() if o != obj), *sweeps, placed]
        options = [(i, k) for k in turns for i in range(len(spots))
                   if clearance(box(obj, i, k), among) >= CLEARANCE]  # fmt: skip
        return any(reached(i, k) for i, k in options)

    ranked = sorted(
        ((i, k) for k in turns for i in range(len(spots))),
        key=lambda ik: (-clearance(box(held_obj, *ik), others), abs(TURNS[ik[1]]),
                        float(np.linalg.norm(spots[ik[0]][:2] - first[:2]))),
    )  # fmt: skip
    fallback = None
    for i, k in ranked:
        if not reached(i, k):
            continue
        fallback = fallback or (spots[i], TURNS[k])
        if all(room_for(obj, box(held_obj, i, k)) for obj in coming):
            return spots[i], TURNS[k]
    return fallback
