"""Controllers for moving objects: ``approach`` and ``retreat`` (hover above a thing, go
up to the home height), ``pick`` / ``pick-out`` (down to the grasp point, close, lift)
and ``place-on`` / ``place-in`` (over a spot, lower the held object until its bottom is
``DROP`` above the surface, open, up), and ``holding_ok``, a pick's effect perceived.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.clearance import carried, transit_height
from osg_control.libero.drive import GRIPPER_CLOSED, GRIPPER_OPEN
from osg_control.libero.edge import (
    EDGE_CREEP,
    EDGE_CREEP_RATE,
    EDGE_CREEP_STEPS,
    pinched,
    slipped,
)
from osg_control.libero.facts import held, region_pose
from osg_control.libero.fixtures import door_point, drawer_front, drawer_hand
from osg_control.libero.grasp import carry_point, grasp_point, grasp_rotation
from osg_control.libero.lay import lies_down, push_over
from osg_control.libero.legs import HOVER, Context, Leg, creep, hold, up
from osg_control.libero.overhang import lean_hover, leaning, slide
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.spots import DROP, SetDown, set_down
from osg_control.libero.tip import release

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
        *lift(ctx, obj),
    ]


def lift(ctx: Context, obj: str) -> list[Leg]:
    """Up ``LIFT``; a pinched object (``edge``) first slowly, and no further when its
    pinch slipped (``edge.slipped``)."""
    if not pinched(ctx, obj):
        return [up(LIFT, GRIPPER_CLOSED)]
    return [creep(EDGE_CREEP, EDGE_CREEP_RATE, GRIPPER_CLOSED, EDGE_CREEP_STEPS),
            up(LIFT - EDGE_CREEP, GRIPPER_CLOSED, until=slipped)]  # fmt: skip


def place(ctx: Context, obj: str, target: str, inside: bool) -> list[Leg]:
    """Turn where the set-down turns ``obj`` (``spots.set_down``: a spot beyond the arm's
    reach moved into it), over the spot at the height ``obj`` was carried in (an object's
    top, a region's floor or a free spot of its top), lower until its bottom is ``DROP``
    above the surface, open, up, and turn the hand back (left turned, the next grasp's
    hand lay past the wrist's limit and the arm wound up against it). An object another
    lands on after it in the region (``Context.tipped``) is let go turned onto its side
    just above the region's box instead (``tip.release``)."""

    chosen: list[SetDown] = []  # decided once: a swinging load moved the spot

    def decided(now: LiberoPercept) -> SetDown:
        if not chosen:
            chosen.append(set_down(ctx, now, target, inside, obj))
        return chosen[0]

    def turn(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, np.ndarray | None]:
        return start.tcp, decided(now).turned  # in place, at the carrying height

    def turn_back(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, np.ndarray | None]:
        return start.tcp, decided(now).before

    def down(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        surface = decided(now).point
        bottom = ctx.scene.extents[obj][0][2]  # the object's bottom below its origin
        origin = surface + np.array([0.0, 0.0, DROP - bottom])
        return origin + carried(now, obj), None

    def over(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        reached = decided(now).over
        if reached is not None:
            return reached, None
        point, _ = down(now, start)  # at the carrying height first: nothing swept
        return np.r_[point[:2], max(point[2], start.tcp[2])], None

    if inside and obj in ctx.tipped:
        return [Leg(turn, GRIPPER_CLOSED, 40, 0.01, transit=True),
                Leg(over, GRIPPER_CLOSED, 30, 0.01),
                *release(ctx, obj, target, lambda now: over(now, now)[0]),
                Leg(turn_back, GRIPPER_OPEN, 40, 0.01, transit=True)]  # fmt: skip
    laid = push_over(ctx, obj, target) if inside and lies_down(ctx, obj, target) else []
    return [Leg(turn, GRIPPER_CLOSED, 40, 0.01, transit=True),
            Leg(over, GRIPPER_CLOSED, 30, 0.01), Leg(down, GRIPPER_CLOSED, 40, 0.01),
            hold(GRIPPER_OPEN, 10), up(0.08, GRIPPER_OPEN), *laid,
            Leg(turn_back, GRIPPER_OPEN, 40, 0.01, transit=True)]  # fmt: skip


def holding_ok(ctx: Context, percept: LiberoPercept, obj: str, start_z: float) -> bool:
    """A pick's effect, perceived: the object is held and came up with the hand."""
    return held(ctx.scene, percept, obj) and percept.position(obj)[2] > start_z + 0.04
