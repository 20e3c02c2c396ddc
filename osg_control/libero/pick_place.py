"""Controllers for moving objects: ``approach`` and ``retreat`` (hover above a thing, go
up to the home height), ``pick`` / ``pick-out`` (down to the grasp point, close, lift)
and ``place-on`` / ``place-in`` (over a spot, lower the held object until its bottom is
``DROP`` above the surface, open, up), and ``holding_ok``, a pick's effect perceived.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.clearance import HAND_BOXES, carried, footprint, transit_height
from osg_control.libero.drive import GRIPPER_CLOSED, GRIPPER_OPEN
from osg_control.libero.edge import pinched
from osg_control.libero.facts import held, holds, region_pose, room
from osg_control.libero.fixtures import door_point, drawer_front, drawer_hand
from osg_control.libero.grasp import carry_point, grasp_point, grasp_rotation
from osg_control.libero.legs import HOVER, Context, Leg, hold, up
from osg_control.libero.overhang import lean_hover, leaning, slide
from osg_control.libero.perception import LiberoPercept

TURN_FIRST = 0.4
"""A hand that must turn more than this [rad] to grasp turns where it is, at least at
the home height, before it moves (turning on the way swung the arm into the object)."""
TOP_CLEARANCE = 0.05
"""Height above an object's top the empty hand hovers at least [m] (a standing book)."""
CARRY = 0.30
"""Height above the target the held object's origin is carried to [m] (a hanging bottle
clears a basket's rim)."""
CARRY_CEILING = 0.10
"""The highest the hand carries an object, above the home height [m]: ``CARRY`` above a
cabinet's top was at the edge of the arm's reach, and the approach ran out of steps."""
HELD_CLEARANCE = 0.05
"""The least height of the held object's bottom above the target's anchor on the way,
over ``CARRY_CEILING`` where it needs [m]: a bottle hung from its neck (``tall``), 13 cm
below the hand, was carried into the wine rack under the ceiling and tipped out of the
hand."""
TRANSIT_SLACK = 0.01
"""How far below its transit height (``clearance.transit_height``) an approach may start
without first going straight up [m]."""
LIFT = 0.12
"""How far a pick lifts before checking the object came with the hand [m]."""
DROP = 0.02
"""Height of the held object's bottom above the surface when released [m]."""
CLEARANCE = 0.02
"""The gap between footprints a place on a region's top keeps where it can [m]."""
EDGE_MARGIN = 0.01
"""How far inside a region's footprint an object is set down at most [m]."""
DESCENT_TOLERANCE = 0.008
"""How near the grasp point a pick's descent closes [m]; farther, it closes when its steps
run out (the hand stopped above: ``stall_close`` states the rule for the learned pick)."""
CLOSING_STEPS = 12
"""Steps a pick holds still closing the gripper before it lifts (the fingers' travel)."""


def anchor(ctx: Context, percept: LiberoPercept, thing: str, holding: bool = False) -> np.ndarray:
    """The point the hand approaches: an object's grasp point (``holding``: the point a
    held object is carried over, ``grasp.carry_point``), a region's centre, a drawer's
    handle, a knob, or a door's push point."""
    scene = ctx.scene
    if thing in percept.objects:
        return (carry_point if holding else grasp_point)(ctx, percept, thing)
    joints = [scene.joints[j] for j in scene.articulated.get(thing, ())]
    if thing in scene.knobs:
        return scene.knobs[thing]
    if thing in scene.leaves:
        return door_point(ctx, percept, thing, joints[0], percept.joint(joints[0].name))
    if thing in scene.regions:
        return region_pose(scene, percept, thing)[0]
    raise KeyError(f"nothing to approach named {thing!r}")


def approach(ctx: Context, thing: str, holding: str | None) -> list[Leg]:
    """Hover above ``thing`` (a drawer: in front of its handle, ``fixtures.drawer_front``);
    with an object in hand, its origin ``CARRY`` above it (the hand at most
    ``CARRY_CEILING`` above the home height, or as high as the held object's bottom needs
    to pass ``HELD_CLEARANCE`` above the target's anchor, and then straight up to that
    height first: on the way a bottle hung from its neck caught on the wine rack). On the
    way the hand (and what it holds) keeps clear above the objects it passes
    (``clearance.transit_height``), going straight up first where it is below that. A
    hand leaning under a drawer hovers back along its own axis (``overhang.lean_hover``)."""

    def goal(now: LiberoPercept) -> tuple[np.ndarray, np.ndarray | None]:
        point = anchor(ctx, now, thing, holding is not None)
        if holding is None and thing in now.objects:  # above the object's top
            top = now.position(thing)[2] + ctx.scene.extents[thing][1][2]
            hover = np.r_[point[:2], max(point[2] + HOVER, top + TOP_CLEARANCE)]
            rot = grasp_rotation(ctx, now, thing)
            if thing not in ctx.grasps and leaning(rot):  # along the leaning hand
                hover = lean_hover(point, float(hover[2]), rot)
            return hover, rot
        region = ctx.scene.regions.get(thing)
        if holding is None and region is not None and region.joint is not None:
            hover = drawer_front(ctx, now, thing) + np.array([0.0, 0.0, HOVER])
            return hover, drawer_hand(ctx, thing)  # in front of its handle
        if holding is None:
            return point + np.array([0.0, 0.0, HOVER]), ctx.base
        offset = carried(now, holding)
        hand = point + np.array([0.0, 0.0, CARRY]) + offset
        clear = point[2] + HELD_CLEARANCE - ctx.scene.extents[holding][0][2] + offset[2]
        ceiling = max(ctx.home_z + CARRY_CEILING, clear)
        return np.r_[hand[:2], min(hand[2], ceiling)], None

    def floor(now: LiberoPercept) -> float:  # above the ceiling: up there first
        point = goal(now)[0]
        high = holding is not None and point[2] > ctx.home_z + CARRY_CEILING
        return max(transit_height(ctx, now, point[:2], holding), point[2] if high else -np.inf)

    def rise(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, np.ndarray | None]:
        return np.r_[now.tcp[:2], max(floor(now), now.tcp[2])], goal(now)[1]

    def target(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, np.ndarray | None]:
        point, rot = goal(now)
        if holding is None and thing in now.objects and rot is not None:
            _, current = ctx.driver.tcp_pose(now.joints)
            if Rotation.from_matrix(current.T @ rot).magnitude() > TURN_FIRST:  # turn in place
                return np.r_[start.tcp[:2], max(start.tcp[2], ctx.home_z)], rot
        return np.r_[point[:2], max(point[2], floor(now))], rot

    gripper = GRIPPER_OPEN if holding is None else GRIPPER_CLOSED
    fine = holding is None and thing in ctx.categories  # the pick that follows descends
    clear = lambda now: now.tcp[2] >= floor(now) - TRANSIT_SLACK  # noqa: E731
    return [Leg(rise, gripper, 40, 0.0, until=clear, transit=True),
            Leg(target, gripper, 90, 0.008 if fine else 0.02, transit=True)]  # fmt: skip


def retreat(ctx: Context, holding: str | None) -> list[Leg]:
    """Straight up to the home height (at least 5 cm)."""

    def target(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        return np.r_[start.tcp[:2], max(ctx.home_z, start.tcp[2] + 0.05)], None

    gripper = GRIPPER_OPEN if holding is None else GRIPPER_CLOSED
    return [Leg(target, gripper, 40, 0.02, transit=True)]


def pick(ctx: Context, obj: str) -> list[Leg]:
    """Over the grasp point first (``approach``'s hover: nothing to do when the approach
    got there; an approach that ran out of steps made the descent sweep sideways into the
    object), then down to it, close, slide out from under the drawers over it
    (``overhang.slide``), lift ``LIFT``."""
    return approach(ctx, obj, None) + [
        Leg(
            lambda now, start: (grasp_point(ctx, now, obj), grasp_rotation(ctx, now, obj)),
            GRIPPER_OPEN,
            40,
            DESCENT_TOLERANCE,
        ),
        hold(GRIPPER_CLOSED, CLOSING_STEPS),
        slide(ctx, obj),
        up(LIFT, GRIPPER_CLOSED),
    ]


def _surface(
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
    pos, mat = region_pose(ctx.scene, percept, target)
    half = np.abs(mat @ ctx.scene.regions[target].size)
    if not inside:
        coming = _still_to_come(ctx, percept, target, held_obj)
        spot = (_row_spot(ctx, percept, pos, held_obj, coming) if coming else
                _free_spot(ctx, percept, pos, half[:2], held_obj))  # fmt: skip
        pos = np.r_[spot[:2], pos[2]]
    elif ctx.scene.regions[target].joint is not None:
        joint = ctx.scene.joints[str(ctx.scene.regions[target].joint)]
        out = joint.axis * joint.opening
        pos = pos + out * (sum(room(ctx.scene, percept, target)) / 2 - pos @ out)
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
    reach = np.maximum(half - EDGE_MARGIN, 0.0)
    grid = np.linspace(-1.0, 1.0, 9)
    spots = [centre[:2] + reach * (a, b) for a in grid for b in grid]
    best = max(spots, key=lambda s: (clearance(s), -float(np.linalg.norm(s - centre[:2]))))
    return np.r_[best, centre[2]]


def _knob_sweeps(ctx: Context, percept: LiberoPercept) -> list[np.ndarray]:
    """The xy boxes the turning hand sweeps at each knob the goal still turns: the palm's
    half-length (``clearance.HAND_BOXES``) round the knob's grip point (a moka pot set
    down beside a frying pan's handle, next to the knob, was pushed off by the turn)."""
    reach = HAND_BOXES[0][0]
    pending = [a.args[0] for a in ctx.goal if a.predicate in ("turnon", "turnoff")
               and a.args[0] in ctx.scene.knobs and not holds(ctx.scene, percept, a)]  # fmt: skip
    return [ctx.scene.knobs[f][:2] + np.array([[-reach], [reach]]) for f in pending]


def place(ctx: Context, obj: str, target: str, inside: bool) -> list[Leg]:
    """Over the spot at the height ``obj`` was carried in (``_surface``: an object's top, a
    region's floor or a free spot of its top), lower until its bottom is ``DROP`` above
    the surface, open, up."""

    chosen: list[np.ndarray] = []  # the spot, decided once: a swinging load moved it

    def down(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        if not chosen:
            chosen.append(_surface(ctx, now, target, inside, obj))
        surface = chosen[0]
        bottom = ctx.scene.extents[obj][0][2]  # the object's bottom below its origin
        origin = surface + np.array([0.0, 0.0, DROP - bottom])
        return origin + carried(now, obj), None

    def over(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        point, _ = down(now, start)  # at the carrying height first: nothing swept
        return np.r_[point[:2], max(point[2], start.tcp[2])], None

    return [Leg(over, GRIPPER_CLOSED, 30, 0.01), Leg(down, GRIPPER_CLOSED, 40, 0.01),
            hold(GRIPPER_OPEN, 10), up(0.08, GRIPPER_OPEN)]  # fmt: skip


def holding_ok(ctx: Context, percept: LiberoPercept, obj: str, start_z: float) -> bool:
    """A pick's effect, perceived: the object is held and came up with the hand."""
    return held(ctx.scene, percept, obj) and percept.position(obj)[2] > start_z + 0.04
