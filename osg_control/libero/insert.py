"""Putting an object into a region behind a hinged door (the microwave's heating region).

Such a region has a roof: an object set down from above, the hand over it, does not go in
(the microwave's inside is 16 cm high, a mug 10 cm, the hand above it 12 cm more). It is
entered sideways through its doorway instead, every quantity read from the scene's
description (``doorway``: the region's box and the side of it the door's leaf, turned to its
closed stop, covers: the doorway's plane and its outward normal) and the percept:

- the grasp is chosen before the pick, because the plan takes the object there next
  (``doorway_grasps``, which the plan executor sets from its plan): top-down on the slice of
  the object furthest out toward the doorway that fits the hand (``outer_grip``: a mug's
  handle), so that the hand stays outside while the object goes in;
- ``approach`` first turns the hand about the vertical until that slice faces out through
  the doorway (``carry_turn``: a mug's only slice that fits, its handle, may face away
  from it), then carries it to in front of the doorway, at the height it goes in at
  (``entry_lift``: ``INSERT_LIFT`` above the region's floor, lower for an object that would
  then meet the roof);
- ``insert`` takes it in until the hand reaches the doorway (``ENTRY``), sets it down, lets
  go and backs out until the hand stands ``PUSH_STANDOFF`` outside the object's outer side,
  then pushes it with the closed hand, pitched ``PUSH_PITCH`` so that the palm stays
  outside and below the roof, until its outer side is ``DOOR_CLEARANCE`` inside the
  doorway's plane (the door then closes over it) but its inner side stays
  ``WALL_CLEARANCE`` off the region's back (``goal_depth``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.clearance import (
    TRANSIT_CLEARANCE,
    carried,
    footprint,
    hang,
    posed_corners,
    transit_height,
)
from osg_control.libero.drive import GRIPPER_CLOSED, GRIPPER_OPEN
from osg_control.libero.fixtures import pitched
from osg_control.libero.grasp import (
    FINGER_HALF,
    GRIP_STEP,
    GRIP_WIDTH,
    fingers_along,
    in_turn_window,
    slab,
    turned_from_start,
)
from osg_control.libero.legs import (
    Context,
    GraspRule,
    Leg,
    Step,
    Target,
    first_places,
    here,
    hold,
    yawed,
)
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.scene import Scene
from osg_control.libero.spots import DROP

PUSH_PITCH = np.radians(45.0)
"""How far the hand pushing an object in tilts its approach toward the inside [rad]: its
palm stays outside and below the roof while the fingertips reach in."""
PALM_CLEAR = 0.02
"""How far below a grasped slice's top the TCP closes at most [m] (robosuite's Panda
hand: the palm is 2.6 cm above the TCP)."""
DOOR_CLEARANCE = 0.015
"""How far inside the doorway's plane the object's outer side is put [m]."""
WALL_CLEARANCE = 0.01
"""How far off the region's back the object's inner side stays at least [m]."""
INSERT_LIFT = 0.03
"""Height of the object's bottom above the region's floor while it goes in [m]."""
ROOF_CLEARANCE = 0.005
"""The least gap between the object's top and the opening's top while it goes in [m]."""
OUTSIDE = 0.03
"""How far outside the doorway's plane the object waits before it goes in [m]."""
ENTRY = 0.04
"""How far outside the doorway's plane the TCP stops while the object goes in held [m]
(robosuite's Panda hand is 3.2 cm thick either side of the TCP: it stays clear of the
roof's front edge)."""
BACK_OUT = 0.06
"""How far the hand backs out along the doorway's normal after the push [m]."""
PUSH_HEIGHT = 0.025
"""Height above the object's bottom the closed hand pushes it at [m] (low: it slides
rather than tips)."""
PUSH_STANDOFF = 0.05
"""How far outside the object's outer side the hand backs out to after letting go, and the
push starts [m]: the hand turns for the push there. (Backed out a fixed 6 cm, it stood 2.4
cm off the end of the mug's handle; the turning hand drifts 1-2 cm inward, and a finger
caught the handle and tipped the mug over: LIBERO-10 task 9, states 14, 16, 23, 32.)"""
PUSH_ARRIVED = 0.005
"""How near its push target the hand is when it has arrived without the object moving on
(the object's box reaches further out than the part the hand meets: a mug turned askew,
its box's corner 1.2 cm beyond its handle) [m]."""
PUSH_DEEPEN = 0.002
"""How much further in the push aims, each step the hand has arrived [m]."""
PUSH_DEEPEST = 0.05
"""How far past ``PUSH_BITE`` the push aims at most [m]."""
PATH_STEP = 0.01
"""Spacing of the points a carried object's way is tested at against a body [m]."""
PUSH_BITE = 0.02
"""How far inside the object's outer side the push aims, the target moving with it [m]."""
HALF_TURN = np.diag([-1.0, -1.0, 1.0])
"""A hand's rotation times this: the same hand turned half a turn about its approach axis
(the fingers alike)."""


@dataclass(frozen=True)
class Doorway:
    """The way into a region behind a hinged door, in the world frame.

    Attributes:
        region: the region.
        normal: the horizontal unit vector out through the doorway.
        plane: ``normal`` . x on the doorway's plane (the hinge line: the shut leaf's
            inner face).
        back: ``normal`` . x on the region's back face.
        centre: the region's centre, across the doorway in the middle of the opening its
            fixture's walls leave there (``opening``).
        floor: the region's floor height [m].
        roof: the height of the top of the opening its fixture's walls leave (``opening``)
            [m].
    """

    region: str
    normal: np.ndarray
    plane: float
    back: float
    centre: np.ndarray
    floor: float
    roof: float

    @property
    def across(self) -> np.ndarray:
        """The horizontal unit vector across the doorway (its normal turned a quarter turn
        counter-clockwise, seen from above)."""
        return np.cross([0.0, 0.0, 1.0], self.normal)


def doorway(scene: Scene, region: str) -> Doorway | None:
    """The doorway into ``region`` when a hinged door (``Scene.leaves``) closes its
    parent, else None: the side of the region's box that the door's leaf, turned to its
    closed stop, covers (the horizontal face whose normal points most toward the closed
    leaf's middle), its plane through the hinge line. (The leaf's far corner is off the
    hinge's line by the leaf's thickness: a normal taken across it was 5 deg askew.)"""
    box = scene.regions.get(region)
    if box is None or box.parent not in scene.leaves:
        return None
    joint = scene.joints[scene.articulated[box.parent][0]]
    turn = Rotation.from_rotvec(joint.axis * (joint.shut - joint.q0)).as_matrix()
    closed = joint.anchor + turn @ (scene.leaves[box.parent] - joint.anchor)
    middle = (joint.anchor + closed) / 2 - box.pos
    sides = [(sign * box.mat[:, i], float(box.size[i])) for i in range(3) for sign in (1.0, -1.0)
             if abs(box.mat[2, i]) < 0.5]  # fmt: skip
    normal, half = max(sides, key=lambda side: float(side[0][:2] @ middle[:2]))
    normal = normal * np.array([1.0, 1.0, 0.0]) / np.linalg.norm(normal[:2])
    extent = np.abs(box.mat) @ box.size
    floor = float(box.pos[2] - extent[2])
    low, high = opening(box.pos - extent, box.pos + extent, scene.walls.get(box.parent, []))
    across = np.cross([0.0, 0.0, 1.0], normal)
    centre = box.pos + across * float(across @ ((low + high) / 2 - box.pos))
    return Doorway(region, normal, float(normal @ joint.anchor), float(normal @ box.pos - half),
                   centre, floor, float(high[2]))  # fmt: skip


def opening(
    low: np.ndarray, high: np.ndarray, walls: list[tuple[np.ndarray, np.ndarray]]
) -> tuple[np.ndarray, np.ndarray]:
    """The box (``low``, ``high``; world, axis-aligned) less the ``walls`` that reach into
    it, each cut off the side of the box it reaches in from least deep (the microwave's
    heating region reaches 5.6 cm into the wall beside its doorway, and 8 mm into its
    floor and roof: a mug centred on the region met that wall, LIBERO-PRO
    ``libero_10_swap`` task 9)."""
    low, high = low.astype(float), high.astype(float)
    for wall_low, wall_high in walls:
        if np.any(wall_high <= low) or np.any(wall_low >= high):
            continue  # clear of the box
        cuts = [(float(wall_high[k] - low[k]), k, 0) for k in range(3)]
        cuts += [(float(high[k] - wall_low[k]), k, 1) for k in range(3)]
        _, k, side = min(cuts)
        if side == 0:
            low[k] = wall_high[k]
        else:
            high[k] = wall_low[k]
    return low, high


def reach(ctx: Context, percept: LiberoPercept, obj: str, direction: np.ndarray) -> float:
    """How far ``obj``'s geometry extends from its origin along ``direction`` (its box's
    corners in its perceived pose)."""
    return float(np.max(posed_corners(ctx, percept, obj) @ direction))


def goal_depth(way: Doorway, outer: float, inner: float) -> float:
    """Where along the doorway's normal the object's origin goes: its outer side
    (``outer`` out from the origin) ``DOOR_CLEARANCE`` inside the plane, unless its inner
    side (``inner`` in from it) would then come closer than ``WALL_CLEARANCE`` to the back
    (the back wins: nothing is pushed through a wall)."""
    return max(way.plane - outer - DOOR_CLEARANCE, way.back + inner + WALL_CLEARANCE)


def entry_lift(ctx: Context, obj: str, way: Doorway) -> float:
    """How high above the region's floor ``obj``'s bottom goes in through ``way``:
    ``INSERT_LIFT``, or lower where its top, upright, would then come closer than
    ``ROOF_CLEARANCE`` to the opening's top (LIBERO-PRO ``_object`` task 9's red mug, 13.3
    cm tall, in a 14.4 cm opening, met the roof's front edge and stalled outside)."""
    low, high = ctx.scene.extents[obj]
    return min(INSERT_LIFT, way.roof - ROOF_CLEARANCE - float(high[2] - low[2]) - way.floor)


def _origin_at(
    ctx: Context, percept: LiberoPercept, obj: str, way: Doorway, depth: float, lift: float
) -> np.ndarray:
    """The origin that puts ``obj`` at ``depth`` along the normal, its extent centred
    across the doorway on the region's centre, its bottom ``lift`` above the floor."""
    across = way.across
    offset = (reach(ctx, percept, obj, across) - reach(ctx, percept, obj, -across)) / 2
    lateral = float(across @ way.centre) - offset
    bottom = ctx.scene.extents[obj][0][2]
    return way.normal * depth + across * lateral + np.array([0.0, 0.0, way.floor + lift - bottom])


def outer_grip(ctx: Context, obj: str, outward: np.ndarray) -> tuple[np.ndarray, int]:
    """The grasp, in ``obj``'s frame, on the slice furthest along ``outward`` (a horizontal
    direction in its frame) that the hand closes round (``GRIP_WIDTH``) with both fingers
    over it: the TCP point (halfway up the slice, or higher so that the palm stays above
    it: ``PALM_CLEAR``) and the axis the fingers slide along.

    Raises:
        KeyError: no slice of ``obj`` fits the hand.
    """
    low, high = ctx.scene.extents[obj]
    best: tuple[float, np.ndarray, int] | None = None
    for axis in (0, 1):
        other = 1 - axis
        for centre in np.arange(low[other], high[other] + 1e-9, GRIP_STEP):
            boxes = slab(ctx, obj, axis, float(centre))
            if not boxes:
                continue
            inside = (min(b[0][other] for b in boxes) <= centre - FINGER_HALF
                      and centre + FINGER_HALF <= max(b[1][other] for b in boxes))  # fmt: skip
            lo, hi = min(b[0][axis] for b in boxes), max(b[1][axis] for b in boxes)
            if not inside or hi - lo > GRIP_WIDTH:
                continue
            point = np.zeros(3)
            point[axis], point[other] = (lo + hi) / 2, centre
            top = max(b[1][2] for b in boxes)
            point[2] = max((min(b[0][2] for b in boxes) + top) / 2, top - PALM_CLEAR)
            score = float(point[:2] @ outward[:2])
            if best is None or score > best[0]:
                best = (score, point, axis)
    if best is None:
        raise KeyError(f"no slice of {obj!r} fits the hand")
    return best[1], best[2]


def reaching_in(ctx: Context, rotation: np.ndarray, way: Doorway) -> np.ndarray:
    """Of a top-down ``rotation`` and the same turned half a turn about the vertical (the
    fingers alike), the one whose x axis points more into the doorway, where the wrist's
    window (``grasp.TURN_WINDOW``) allows: with the other the arm wound its wrist and
    stalled short of the doorway (LIBERO-10 task 9, state 4)."""
    turned = rotation @ HALF_TURN
    allowed = in_turn_window(turned_from_start(ctx, turned))
    inward = allowed and turned[:, 0] @ way.normal < rotation[:, 0] @ way.normal
    return turned if inward else rotation


def carry_turn(
    ctx: Context, rotation: np.ndarray, facing: np.ndarray, way: Doorway
) -> float | None:
    """The angle from the start's (``grasp.turned_from_start``) that a top-down hand at
    ``rotation``, holding an object on its side ``facing`` (horizontal, from the object's
    origin toward the grasped slice), turns to about the vertical so that the slice faces
    out through the doorway (its normal); None where that turn leaves the wrist's window
    (``grasp.in_turn_window``)."""
    cross = facing[0] * way.normal[1] - facing[1] * way.normal[0]
    turn = float(np.arctan2(cross, facing[:2] @ way.normal[:2]))
    now = turned_from_start(ctx, rotation)
    for end in (now + turn, now + turn - np.sign(turn) * 2 * np.pi):
        if in_turn_window(end):
            return end
    return None


def doorway_grasp(ctx: Context, obj: str, way: Doorway) -> GraspRule:
    """The grasp for taking ``obj`` through ``way``: top-down on ``outer_grip``'s slice,
    chosen at the rule's first use and then kept (a slice chosen anew each step jumped
    elsewhere when the descending fingers tilted the object); of the two hands alike,
    ``reaching_in``'s unless only the other can turn the slice out through the doorway
    (``carry_turn``)."""
    chosen: list[tuple[np.ndarray, int]] = []

    def rule(percept: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        pos, rot = percept.objects[obj]
        if not chosen:
            chosen.append(outer_grip(ctx, obj, rot.T @ way.normal))
        point, axis = chosen[0]
        hand = reaching_in(ctx, fingers_along(ctx, rot[:, axis]), way)
        other = hand @ HALF_TURN
        facing = rot @ point
        if (
            carry_turn(ctx, hand, facing, way) is None
            and carry_turn(ctx, other, facing, way) is not None
        ):
            hand = other
        return pos + facing, hand

    return rule


def doorway_grasps(ctx: Context, steps: list[Step]) -> dict[str, GraspRule]:
    """The grasps a plan's ``steps`` need: for each object whose next place is into a
    region behind a door, ``doorway_grasp`` (the others keep the top-down one)."""
    grasps: dict[str, GraspRule] = {}
    for operator, obj, target in first_places(steps):
        way = doorway(ctx.scene, target) if operator == "place-in" else None
        if way is not None:
            grasps[obj] = doorway_grasp(ctx, obj, way)
    return grasps


def _upright(percept: LiberoPercept, obj: str) -> np.ndarray:
    """``obj``'s perceived rotation less any tilt: its yaw about the vertical."""
    x = percept.objects[obj][1][:, 0]
    return yawed(float(np.arctan2(x[1], x[0])))


def crosses(start: np.ndarray, end: np.ndarray, low: np.ndarray, high: np.ndarray) -> bool:
    """Whether the xy segment from ``start`` to ``end`` passes through the xy box
    (``low``, ``high``), tested every ``PATH_STEP`` along it."""
    count = int(np.ceil(np.linalg.norm(end[:2] - start[:2]) / PATH_STEP)) + 1
    points = np.linspace(start[:2], end[:2], count + 1)
    return bool(np.any(np.all((points > low[:2]) & (points < high[:2]), axis=1)))


def turn_out(ctx: Context, way: Doorway, holding: str) -> Leg:
    """Turn the hand in place about the vertical until the grasped slice of ``holding``
    (where the TCP is from its origin) faces out through the doorway (``carry_turn``, decided
    once; no turn where it leaves the wrist's window): at most a quarter turn ahead at a time,
    so that a half turn goes the way the window allows."""
    end: list[float | None] = []

    def target(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        if not end:
            end.append(carry_turn(ctx, ctx.rotation, carried(start, holding), way))
        if end[0] is None:
            return start.tcp, ctx.rotation
        yaw = turned_from_start(ctx, ctx.driver.tcp_pose(now.joints)[1])
        return start.tcp, yawed(
            yaw + float(np.clip(end[0] - yaw, -np.pi / 2, np.pi / 2))
        ) @ ctx.base

    return Leg(target, GRIPPER_CLOSED, 90, 0.03, transit=True)


def approach(ctx: Context, region: str, holding: str) -> list[Leg]:
    """Turn ``holding``'s grasped slice out toward the doorway into ``region``
    (``turn_out``), and carry it to in front of the doorway: its inner side ``OUTSIDE``
    out of the plane, its bottom ``entry_lift`` above the region's floor; first across to
    the doorway's line, then in along it, its bottom kept ``TRANSIT_CLEARANCE`` over what
    it passes (``clearance.transit_height``), then down. (Carried diagonally, the hand met
    a door open less than 90 deg near its leaf's tip and swung it toward shut; straight in
    at its entry height, the object ran into another standing in front of the doorway:
    LIBERO-PRO ``_task`` task 9.)
    Where its straight way there passes through the door fixture's body
    (``Scene.housings``: the object starts behind or beside it), it goes up until its
    bottom is ``TRANSIT_CLEARANCE`` above the body, over to above the doorway's front (at
    the transit pace: in free space), then down (decided once, at the start)."""
    way = doorway(ctx.scene, region)
    assert way is not None

    def front(now: LiberoPercept) -> np.ndarray:
        depth = way.plane + reach(ctx, now, holding, -way.normal) + OUTSIDE
        return _origin_at(ctx, now, holding, way, depth, entry_lift(ctx, holding, way))

    def target(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        return front(now) + carried(now, holding), None

    def line_up(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        offset = float(way.across @ (target(now, start)[0] - start.tcp))
        return start.tcp + way.across * offset, None

    def over_in(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        point = target(now, start)[0]
        floor = transit_height(ctx, now, point[:2], holding)
        return np.r_[point[:2], max(point[2], floor)], None

    legs = [
        Leg(line_up, GRIPPER_CLOSED, 60, 0.01),
        Leg(over_in, GRIPPER_CLOSED, 90, 0.015),
        Leg(target, GRIPPER_CLOSED, 40, 0.015),
    ]
    housing = ctx.scene.housings.get(ctx.scene.regions[region].parent)
    if housing is None:
        return [turn_out(ctx, way, holding), *legs]
    route: list[float] = []  # the TCP height that carries the object over the body, or none

    def over(now: LiberoPercept) -> float | None:
        if not route:
            sides = footprint(ctx, now, holding) - now.position(holding)[:2]
            low, high = housing[0][:2] - sides[1], housing[1][:2] - sides[0]
            blocked = crosses(now.position(holding), front(now), low, high)
            top = float(housing[1][2]) + TRANSIT_CLEARANCE + hang(ctx, now, holding)
            route.append(top if blocked else -np.inf)
        return route[0] if np.isfinite(route[0]) else None

    def rise(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        height = over(now)
        return np.r_[start.tcp[:2], start.tcp[2] if height is None else height], None

    def across(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        height = over(now)
        point = target(now, start)[0]
        return (start.tcp if height is None else np.r_[point[:2], height]), None

    def routed(now: LiberoPercept) -> bool:
        return over(now) is None

    return [turn_out(ctx, way, holding),
            Leg(rise, GRIPPER_CLOSED, 40, 0.015, until=routed, transit=True),
            Leg(across, GRIPPER_CLOSED, 90, 0.02, until=routed, transit=True),
            *legs]  # fmt: skip


def insert(ctx: Context, obj: str, region: str) -> list[Leg]:
    """In through the doorway until the TCP is ``ENTRY`` outside its plane, down until the
    object, upright, would stand ``DROP`` above the floor, let go, back out until the TCP is
    ``PUSH_STANDOFF`` outside the object's outer side (perceived); then push its outer side
    with the closed hand, pitched, ``PUSH_HEIGHT`` above its bottom, until its origin is at
    ``goal_depth`` (perceived), and back out ``BACK_OUT``."""
    way = doorway(ctx.scene, region)
    assert way is not None
    n = way.normal
    across = way.across

    def entry(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        hand = carried(now, obj)
        depth = way.plane + ENTRY - float(n @ hand)
        return _origin_at(ctx, now, obj, way, depth, entry_lift(ctx, obj, way)) + hand, None

    def down(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        grip_z = outer_grip(ctx, obj, _upright(now, obj).T @ n)[0][2]
        bottom = ctx.scene.extents[obj][0][2]
        return np.r_[start.tcp[:2], way.floor + DROP - bottom + grip_z], None

    push_turn: list[np.ndarray] = []  # the pushing hand's rotation, decided once

    def behind(standoff: float, deepen: bool = False) -> Target:
        bite = [0.0]  # how far past ``standoff`` the push aims now (``deepen``)

        def target(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
            if not push_turn:
                level = fingers_along(ctx, across)
                push_turn.append(pitched(level, -n, PUSH_PITCH))
            origin = now.position(obj)
            side = float(n @ origin) + reach(ctx, now, obj, n) + standoff
            if deepen and float(n @ now.tcp) < side + bite[0] + PUSH_ARRIVED:
                bite[0] = max(bite[0] - PUSH_DEEPEN, -PUSH_DEEPEST)
            point = n * (side + bite[0]) + across * float(across @ origin)
            return np.r_[point[:2], origin[2] + PUSH_HEIGHT], push_turn[0]

        return target

    def clear_out(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        side = float(n @ now.position(obj)) + reach(ctx, now, obj, n) + PUSH_STANDOFF
        return start.tcp + n * (side - float(n @ start.tcp)), None

    def pushed(now: LiberoPercept) -> bool:
        outer, inner = reach(ctx, now, obj, n), reach(ctx, now, obj, -n)
        return float(n @ now.position(obj)) <= goal_depth(way, outer, inner)

    return [
        Leg(entry, GRIPPER_CLOSED, 40, 0.01), Leg(down, GRIPPER_CLOSED, 30, 0.01),
        hold(GRIPPER_OPEN, 10), Leg(clear_out, GRIPPER_OPEN, 30, 0.01),
        Leg(behind(PUSH_STANDOFF), GRIPPER_CLOSED, 40, 0.01),
        Leg(behind(-PUSH_BITE, deepen=True), GRIPPER_CLOSED, 50, 0.0, pushed),
        Leg(here(tuple(n * BACK_OUT)), GRIPPER_CLOSED, 20, 0.02),
    ]  # fmt: skip
