"""Scripted controllers for the operators of the lifted domain ``osg-libero``: each turns
one ground operator into legs of TCP motion, every target computed from the current
percept (``perception.LiberoPercept``) and the scene's static description, driven by our
IK (``drive.JointTargetDriver``).

They are the first skills the plans run and the scripted collectors Algorithm 1's data
will come from: told which operator to run, they script its motion; they are not learned.

- ``approach ?x``: hover above ``?x`` (its grasp point, region, handle, knob or door).
- ``retreat ?x``: straight up to the home height (the node ``home`` is the safe height,
  not a fixed pose: going back to one would spend the step budget).
- ``pick ?o ?s`` / ``pick-out ?o ?r``: down to the grasp point, close, lift. A bowl is
  grasped at its rim (``RIM_GRASP``), anything else just above its origin.
- ``place-on ?o ?t`` / ``place-in ?o ?r``: over the target so the held object's origin is
  above the target's, lower until its bottom is ``DROP`` above the surface (``on``) or the
  region's floor (``in``), open, up.
- ``open`` / ``close ?x ?r`` on a drawer: grasp its handle and pull past LIBERO's open
  threshold, or push its front to the closed stop with the closed hand.
- ``close ?x ?r`` on a door: push its leaf round the hinge, the push point leading the
  sensed door angle.
- ``turn-on`` / ``turn-off ?f``: grasp the knob and turn the wrist about the knob's axis
  until the sensed angle is past LIBERO's threshold.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.drive import GRIPPER_CLOSED, GRIPPER_OPEN, JointTargetDriver
from osg_control.libero.facts import held, region_pose
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.scene import Joint, Scene

Target = Callable[[LiberoPercept, LiberoPercept], tuple[np.ndarray, np.ndarray | None]]
"""(percept now, percept when the leg started) -> TCP position and rotation (None: the
controller's grasp rotation)."""

TURN_WINDOW = np.radians(15.0)
"""How far past a quarter turn from the start a grasp may turn the wrist [rad]."""
TURN_FIRST = 0.4
"""A hand that must turn more than this [rad] to grasp turns where it is, at least at
the home height, before it moves (turning on the way swung the arm into the object)."""
TURN_TOLERANCE = 0.1
"""A leg that names a rotation is reached only within this of it [rad]."""
HOVER = 0.10
"""Height above a thing's grasp point the empty hand approaches [m]."""
TOP_CLEARANCE = 0.05
"""Height above an object's top the empty hand hovers at least [m] (a standing book)."""
CARRY = 0.30
"""Height above the target the held object's origin is carried to [m] (a hanging bottle
clears a basket's rim)."""
LIFT = 0.12
"""How far a pick lifts before checking the object came with the hand [m]."""
DROP = 0.02
"""Height of the held object's bottom above the surface when released [m]."""
CLEARANCE = 0.02
"""The gap between footprints a place on a region's top keeps where it can [m]."""
EDGE_MARGIN = 0.01
"""How far inside a region's footprint an object is set down at most [m]."""
RIM_GRASP = ("bowl", "mug")
"""Object categories grasped at the rim (their origin is inside them, or they are wider
than the open hand)."""
RIM_INSET = 0.012
"""How far inside the rim's outer radius the TCP closes [m]."""
ROUND = 1.3
GRASP_ABOVE_ORIGIN = 0.005
"""The grasp height above an object's origin tried first [m] (2 cm higher missed the flat
boxes: cream cheese, butter, pudding)."""
GRIP_WIDTH = 0.07
"""The widest side the open hand (about 8 cm) closes round with a margin [m]."""
BAND = 0.02
"""The least height of an object's part the fingertips close on [m]."""
FINGER_HALF = 0.012
"""Half the width of a finger across its sliding direction [m]."""
GRIP_STEP = 0.005
"""The spacing of the slices ``grip`` tries [m]."""
"""An object whose horizontal sides differ by less than this ratio is grasped unturned."""
RIM_DEPTH = 0.02
"""How far below a rim the fingertips close [m]."""
PUSH_STANDOFF = 0.05
"""Distance from a drawer's handle or a door's leaf the pushing hand starts at [m]."""
DOOR_LEAD = 0.35
"""How far ahead of the sensed door angle the push point is put [rad]."""
DOOR_RADIUS = 0.6
"""Where a door is pushed, as a fraction of the leaf's length from the hinge."""
KNOB_TURN = 0.4
"""How far past LIBERO's threshold a knob is turned [rad]."""
PUSH_PITCH = np.radians(35.0)
"""How far the hand pushing a drawer shut is tilted toward the cabinet (``_pitched``)."""
DRAWER_MARGIN = 0.02
"""How far past LIBERO's open threshold a drawer is pulled [m]."""


@dataclass(frozen=True)
class Leg:
    """One leg: move the TCP to a target with a gripper command until within
    ``tolerance`` (0: for all ``steps``), or until ``until`` holds, or ``steps`` run out."""

    target: Target
    gripper: float
    steps: int
    tolerance: float = 0.01
    until: Callable[[LiberoPercept], bool] | None = None


@dataclass
class Context:
    """What every controller of an episode shares: the scene, the IK driver, the top-down
    rotation of the episode's start (``base``, which fixture controllers use), the last
    commanded rotation (``rotation``: a leg that names none keeps it), the home height,
    the objects' categories and where the arm's base stands (``base_xy``)."""

    scene: Scene
    driver: JointTargetDriver
    base: np.ndarray
    home_z: float
    categories: dict[str, str]
    base_xy: np.ndarray

    def __post_init__(self) -> None:
        self.rotation = self.base


class LegRunner:
    """Runs legs in order; ``act`` returns the next action, or None when all are done."""

    def __init__(self, legs: list[Leg], context: Context) -> None:
        self.legs, self.context = legs, context
        self.index, self.steps = 0, 0
        self.start: LiberoPercept | None = None

    def act(self, percept: LiberoPercept) -> np.ndarray | None:
        """The next JOINT_POSITION action, or None when the last leg is done."""
        while self.index < len(self.legs):
            leg = self.legs[self.index]
            if self.start is None:
                self.start = percept
            pos, rot = leg.target(percept, self.start)
            near = leg.tolerance > 0 and np.linalg.norm(percept.tcp - pos) < leg.tolerance
            if near and rot is not None:  # a leg that turns the hand also waits for the turn
                _, now = self.context.driver.tcp_pose(percept.joints)
                near = Rotation.from_matrix(now.T @ rot).magnitude() < TURN_TOLERANCE
            stop = leg.until is not None and leg.until(percept)
            if not (near or stop) and self.steps < leg.steps:
                self.steps += 1
                if rot is not None:
                    self.context.rotation = rot
                return self.context.driver.action(
                    percept.joints, pos, self.context.rotation, leg.gripper
                )
            self.index, self.steps, self.start = self.index + 1, 0, None
        return None


def _here(offset: tuple[float, float, float]) -> Target:
    return lambda now, start: (start.tcp + offset, None)


def hold(gripper: float, steps: int) -> Leg:
    """Stay where the leg starts, commanding the gripper, for ``steps``."""
    return Leg(_here((0.0, 0.0, 0.0)), gripper, steps, 0.0)


def up(height: float, gripper: float) -> Leg:
    return Leg(_here((0.0, 0.0, height)), gripper, 30, 0.02)


def _yaw(rotation: np.ndarray, angle: float) -> np.ndarray:
    return Rotation.from_rotvec([0.0, 0.0, angle]).as_matrix() @ rotation


@dataclass(frozen=True)
class Grip:
    """Where the fingers close on an object, in its own frame: the TCP point, and the
    object axis (0: x, 1: y) they slide along (None: as the hand comes, a round object)."""

    point: np.ndarray
    axis: int | None


def _slab(ctx: Context, obj: str, axis: int, centre: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The object's geoms a finger pair sliding along ``axis`` sweeps down through when
    centred at ``centre`` on the other horizontal axis."""
    other = 1 - axis
    return [(lo, hi) for lo, hi in ctx.scene.parts[obj]
            if lo[other] < centre + FINGER_HALF and hi[other] > centre - FINGER_HALF]  # fmt: skip


def grip(ctx: Context, obj: str) -> Grip:
    """Where to grasp ``obj`` from above: just above its origin across its narrower side
    when everything the fingers pass on the way down fits between them (``GRIP_WIDTH``);
    else the slice of the object, along either horizontal axis, that fits with the least
    width (a moka pot's handle), at the origin's height clamped into that slice."""
    low, high = ctx.scene.extents[obj]
    width = high[:2] - low[:2]
    axis = int(np.argmin(width))
    default = np.array([0.0, 0.0, GRASP_ABOVE_ORIGIN])
    if max(width) < ROUND * min(width) and min(width) <= GRIP_WIDTH:
        return Grip(default, None)
    candidates = []
    for a in (axis, 1 - axis):
        for centre in np.arange(low[1 - a], high[1 - a] + 1e-9, GRIP_STEP):
            boxes = _slab(ctx, obj, a, float(centre))
            if not boxes:
                continue
            lo_a, hi_a = min(b[0][a] for b in boxes), max(b[1][a] for b in boxes)
            if hi_a - lo_a > GRIP_WIDTH:
                continue
            top, bottom = max(b[1][2] for b in boxes), min(b[0][2] for b in boxes)
            point = np.zeros(3)
            point[a], point[1 - a] = (lo_a + hi_a) / 2, centre
            point[2] = max(bottom + BAND / 2, min(GRASP_ABOVE_ORIGIN, top - BAND / 2))
            candidates.append((hi_a - lo_a + abs(centre) * 0.1, a, point))
            if a == axis and abs(centre) < GRIP_STEP / 2 + 1e-9:
                return Grip(point, a)
    if not candidates:
        return Grip(default, axis)
    _, a, point = min(candidates, key=lambda c: c[0])
    return Grip(point, a)


def grasp_rotation(ctx: Context, percept: LiberoPercept, obj: str) -> np.ndarray:
    """The top-down grasp turned about the vertical so that the fingers close across the
    side ``grasp_band`` chose (unturned for a round object)."""
    if _rim(ctx, obj):  # the hand's long side across the reach: it fits under cabinets
        return fingers_along(ctx, percept.position(obj) - ctx.base_xy)
    axis = grip(ctx, obj).axis
    if axis is None:
        return ctx.base
    return fingers_along(ctx, percept.objects[obj][1][:, axis])


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
             if abs(a) <= np.pi / 2 + TURN_WINDOW]  # fmt: skip
    return max(turns, key=lambda r: float(np.trace(r.T @ ctx.rotation)))


def _rim(ctx: Context, obj: str) -> bool:
    return any(word in ctx.categories.get(obj, "") for word in RIM_GRASP)


def grasp_point(ctx: Context, percept: LiberoPercept, obj: str) -> np.ndarray:
    """Where the TCP closes on ``obj``: just above its origin, or on a bowl's or mug's rim
    (on the side away from a handle: the side of the rim further from the box's centre)."""
    pos, rot = percept.objects[obj]
    low, high = ctx.scene.extents[obj]
    if not _rim(ctx, obj):
        return pos + rot @ grip(ctx, obj).point
    axis = grasp_rotation(ctx, percept, obj)[:, 1] * np.array([1.0, 1.0, 0.0])
    axis /= np.linalg.norm(axis)
    radius = float(min(np.abs(low[:2]).min(), np.abs(high[:2]).min())) - RIM_INSET
    centre = pos + rot @ ((low + high) / 2)
    rims = [pos + side * radius * axis for side in (1.0, -1.0)]
    rim = max(rims, key=lambda p: float(np.linalg.norm((p - centre)[:2])))
    return np.r_[rim[:2], pos[2] + high[2] - RIM_DEPTH]


def anchor(ctx: Context, percept: LiberoPercept, thing: str) -> np.ndarray:
    """The point the hand approaches: an object's grasp point, a region's centre, a
    drawer's handle, a knob, or a door's push point."""
    scene = ctx.scene
    if thing in percept.objects:
        return grasp_point(ctx, percept, thing)
    joints = [scene.joints[j] for j in scene.articulated.get(thing, ())]
    if thing in scene.knobs:
        return scene.knobs[thing]
    if thing in scene.leaves:
        return _door_point(ctx, percept, thing, joints[0], percept.joint(joints[0].name))
    if thing in scene.regions:
        return region_pose(scene, percept, thing)[0]
    raise KeyError(f"nothing to approach named {thing!r}")


def _carried_offset(percept: LiberoPercept, obj: str | None) -> np.ndarray:
    """TCP minus the held object's origin (zero when nothing is held)."""
    return np.zeros(3) if obj is None else percept.tcp - percept.position(obj)


def approach(ctx: Context, thing: str, holding: str | None) -> list[Leg]:
    """Hover above ``thing``; with an object in hand, its origin ``CARRY`` above it."""

    def target(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, np.ndarray | None]:
        point = anchor(ctx, now, thing)
        if holding is None and thing in now.objects:  # above the object's top
            top = now.position(thing)[2] + ctx.scene.extents[thing][1][2]
            hover = np.r_[point[:2], max(point[2] + HOVER, top + TOP_CLEARANCE)]
            turn = grasp_rotation(ctx, now, thing)
            _, rot = ctx.driver.tcp_pose(now.joints)
            if Rotation.from_matrix(rot.T @ turn).magnitude() > TURN_FIRST:  # turn in place
                return np.r_[start.tcp[:2], max(start.tcp[2], ctx.home_z)], turn
            return hover, turn
        if holding is None:
            return point + np.array([0.0, 0.0, HOVER]), ctx.base
        return point + np.array([0.0, 0.0, CARRY]) + _carried_offset(now, holding), None

    gripper = GRIPPER_OPEN if holding is None else GRIPPER_CLOSED
    fine = holding is None and thing in ctx.categories  # the pick that follows descends
    return [Leg(target, gripper, 90, 0.008 if fine else 0.02)]


def retreat(ctx: Context, holding: str | None) -> list[Leg]:
    """Straight up to the home height (at least 5 cm)."""

    def target(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        return np.r_[start.tcp[:2], max(ctx.home_z, start.tcp[2] + 0.05)], None

    return [Leg(target, GRIPPER_OPEN if holding is None else GRIPPER_CLOSED, 40, 0.02)]


def pick(ctx: Context, obj: str) -> list[Leg]:
    """Over the grasp point first (``approach``'s hover: nothing to do when the approach
    got there; an approach that ran out of steps made the descent sweep sideways into the
    object), then down to it, close, lift ``LIFT``."""
    return approach(ctx, obj, None) + [
        Leg(
            lambda now, start: (grasp_point(ctx, now, obj), grasp_rotation(ctx, now, obj)),
            GRIPPER_OPEN,
            40,
            0.008,
        ),
        hold(GRIPPER_CLOSED, 12),
        up(LIFT, GRIPPER_CLOSED),
    ]


def _surface(
    ctx: Context, percept: LiberoPercept, target: str, inside: bool, held_obj: str
) -> np.ndarray:
    """The point the held object ``held_obj`` is set down over: an object's top centre, a
    region's floor centre (``in``) or a free spot of its top (``on``, ``_free_spot``)."""
    if target in percept.objects:
        pos, _ = percept.objects[target]
        return pos + np.array([0.0, 0.0, ctx.scene.extents[target][1][2]])
    pos, mat = region_pose(ctx.scene, percept, target)
    half = np.abs(mat @ ctx.scene.regions[target].size)
    if not inside:
        pos = _free_spot(ctx, percept, pos, half[:2], held_obj)
    return pos + np.array([0.0, 0.0, -half[2] if inside else half[2]])


def _footprint(ctx: Context, percept: LiberoPercept, obj: str) -> np.ndarray:
    """An object's perceived footprint: the world xy box (lower, upper) round its
    collision geometry (a moka pot's handle included)."""
    pos, rot = percept.objects[obj]
    low, high = ctx.scene.extents[obj]
    corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                        for z in (low[2], high[2])])  # fmt: skip
    world = pos[:2] + (corners @ rot.T)[:, :2]
    return np.array([world.min(axis=0), world.max(axis=0)])


def _free_spot(
    ctx: Context, percept: LiberoPercept, centre: np.ndarray, half: np.ndarray, held_obj: str
) -> np.ndarray:
    """Where on a region's top to set ``held_obj`` down: its centre when it would stand
    ``CLEARANCE`` clear of every other object's footprint there, else the point of the
    region's footprint (less ``EDGE_MARGIN``) whose footprint stands clearest of them (up to
    ``CLEARANCE``), the nearest the centre among equals (the second moka pot on a stove)."""
    own = _footprint(ctx, percept, held_obj) - percept.position(held_obj)[:2]
    others = [_footprint(ctx, percept, o) for o in percept.objects if o != held_obj]

    def clearance(spot: np.ndarray) -> float:
        box = own + spot
        gaps = [float(np.max(np.maximum(o[0] - box[1], box[0] - o[1]))) for o in others]
        return min([CLEARANCE, *gaps])

    if clearance(centre[:2]) >= CLEARANCE:
        return centre
    reach = np.maximum(half - EDGE_MARGIN, 0.0)
    grid = np.linspace(-1.0, 1.0, 9)
    spots = [centre[:2] + reach * (a, b) for a in grid for b in grid]
    best = max(spots, key=lambda s: (clearance(s), -float(np.linalg.norm(s - centre[:2]))))
    return np.r_[best, centre[2]]


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
        return origin + _carried_offset(now, obj), None

    def over(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        point, _ = down(now, start)  # at the carrying height first: nothing swept
        return np.r_[point[:2], max(point[2], start.tcp[2])], None

    return [Leg(over, GRIPPER_CLOSED, 30, 0.01), Leg(down, GRIPPER_CLOSED, 40, 0.01),
            hold(GRIPPER_OPEN, 10), up(0.08, GRIPPER_OPEN)]  # fmt: skip


def _pitched(rotation: np.ndarray, toward: np.ndarray) -> np.ndarray:
    """``rotation`` with its approach axis (the TCP's z, down) tilted ``PUSH_PITCH`` toward
    ``toward``, about the fingers' axis: the wrist and forearm then stay back and up, clear
    of a cabinet's top while the fingertips push its bottom drawer."""
    tilts = [Rotation.from_rotvec(rotation[:, 1] * a).as_matrix() @ rotation
             for a in (PUSH_PITCH, -PUSH_PITCH)]  # fmt: skip
    return max(tilts, key=lambda r: float(r[:, 2] @ toward))


def _handle(ctx: Context, percept: LiberoPercept, joint: Joint, q: float) -> np.ndarray:
    """A drawer's handle when its joint is at ``q``."""
    return ctx.scene.handles[joint.name] + joint.axis * (q - joint.q0)


def drawer(ctx: Context, region: str, opening: bool) -> list[Leg]:
    """Open: grasp the handle, pull past the open threshold. Close: push the handle's
    face with the closed hand to the closed stop."""
    joint = ctx.scene.joints[ctx.scene.articulated[region][0]]
    out = joint.axis * joint.opening  # the direction the drawer comes out
    across = fingers_along(ctx, np.cross(out, [0.0, 0.0, 1.0]))  # the hand thin along out
    sensed = lambda p: p.joint(joint.name)  # noqa: E731
    if opening:  # pinch the handle's bar front and back, the fingers along ``out``
        goal = joint.active + joint.opening * DRAWER_MARGIN
        along = fingers_along(ctx, out)
        return [
            Leg(lambda now, s: (_handle(ctx, now, joint, sensed(now)), along), GRIPPER_OPEN,
                40, 0.008),
            hold(GRIPPER_CLOSED, 12),
            Leg(lambda now, s: (_handle(ctx, now, joint, goal), along), GRIPPER_CLOSED, 60,
                0.01, lambda p: joint.is_active(sensed(p) - joint.opening * DRAWER_MARGIN)),
            hold(GRIPPER_OPEN, 8),
            Leg(_here(tuple(out * PUSH_STANDOFF)), GRIPPER_OPEN, 20, 0.02),
        ]  # fmt: skip
    shut = joint.limits[1] if joint.opening < 0 else joint.limits[0]
    across = _pitched(across, -out)
    front = lambda now, q: _handle(ctx, now, joint, q) + out * PUSH_STANDOFF  # noqa: E731
    return [
        Leg(lambda now, s: (front(now, sensed(s)) + [0, 0, HOVER], across), GRIPPER_CLOSED,
            40, 0.02),
        Leg(lambda now, s: (front(now, sensed(s)), across), GRIPPER_CLOSED, 30, 0.015),
        Leg(lambda now, s: (_handle(ctx, now, joint, shut) - out * 0.03, across),
            GRIPPER_CLOSED, 60, 0.035),
        Leg(_here(tuple(out * PUSH_STANDOFF)), GRIPPER_CLOSED, 20, 0.02),
    ]  # fmt: skip


def _door_point(
    ctx: Context, percept: LiberoPercept, door: str, joint: Joint, q: float
) -> np.ndarray:
    """The push point on the door's closing side when the door is at ``q``, standing off
    ``PUSH_STANDOFF`` / 2 from the leaf."""
    tip = ctx.scene.leaves[door]
    turn = Rotation.from_rotvec(joint.axis * (q - joint.q0)).as_matrix()
    radial = turn @ (tip - joint.anchor)
    radial -= (radial @ joint.axis) * joint.axis
    closing = np.cross(joint.axis, radial / np.linalg.norm(radial)) * -joint.opening
    point = joint.anchor + DOOR_RADIUS * radial - closing * PUSH_STANDOFF / 2
    return np.r_[point[:2], joint.anchor[2]]


def door(ctx: Context, fixture: str) -> list[Leg]:
    """Close a door: from beside the leaf, push the point ``DOOR_LEAD`` ahead of the
    sensed angle round the hinge, up to the closed stop."""
    joint = ctx.scene.joints[ctx.scene.articulated[fixture][0]]
    shut = joint.limits[1] if joint.opening < 0 else joint.limits[0]

    def ahead(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        q = now.joint(joint.name) - joint.opening * DOOR_LEAD
        q = min(q, shut) if joint.opening < 0 else max(q, shut)
        return _door_point(ctx, now, fixture, joint, q), None

    at = lambda now, s: _door_point(ctx, now, fixture, joint, s.joint(joint.name))  # noqa: E731
    return [
        Leg(lambda now, s: (at(now, s) + [0, 0, HOVER], ctx.base), GRIPPER_CLOSED, 40, 0.02),
        Leg(lambda now, s: (at(now, s), ctx.base), GRIPPER_CLOSED, 30, 0.015),
        Leg(ahead, GRIPPER_CLOSED, 100, 0.015),
        up(HOVER, GRIPPER_CLOSED),
    ]


def knob(ctx: Context, fixture: str, on: bool) -> list[Leg]:
    """Grasp the knob, turn the wrist about its axis until the sensed angle is
    ``KNOB_TURN`` past LIBERO's threshold, let go, up."""
    joint = ctx.scene.joints[ctx.scene.articulated[fixture][0]]
    point = ctx.scene.knobs[fixture]
    sign = joint.opening if on else -joint.opening
    goal = (joint.active if on else joint.rest) + sign * KNOB_TURN

    def turn(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        left = goal - now.joint(joint.name)
        step = float(np.clip(left, -0.6, 0.6))
        _, rot = ctx.driver.tcp_pose(now.joints)
        spin = Rotation.from_rotvec(joint.axis * step).as_matrix()
        return point, spin @ rot

    def done(p: LiberoPercept) -> bool:
        return bool((p.joint(joint.name) - goal) * sign > 0)

    return [
        Leg(lambda now, s: (point + [0, 0, HOVER], ctx.base), GRIPPER_OPEN, 40, 0.02),
        Leg(lambda now, s: (point, ctx.base), GRIPPER_OPEN, 30, 0.006),
        hold(GRIPPER_CLOSED, 12),
        Leg(turn, GRIPPER_CLOSED, 60, 0.0, done),
        hold(GRIPPER_OPEN, 8),
        up(HOVER, GRIPPER_OPEN),
    ]


def operator_legs(
    ctx: Context, operator: str, args: tuple[str, ...], holding: str | None
) -> list[Leg]:
    """The legs of one ground operator of ``osg-libero``.

    Raises:
        KeyError: an operator no controller runs, or a thing the scene does not describe.
    """
    if operator == "approach":
        return approach(ctx, args[0], holding)
    if operator == "retreat":
        return retreat(ctx, holding)
    if operator in ("pick", "pick-out"):
        return pick(ctx, args[0])
    if operator in ("place-on", "place-in"):
        return place(ctx, args[0], args[1], inside=operator == "place-in")
    if operator in ("open", "close") and args[0] in ctx.scene.leaves and operator == "close":
        return door(ctx, args[0])
    if operator in ("open", "close") and args[0] in ctx.scene.regions:
        return drawer(ctx, args[0], opening=operator == "open")
    if operator in ("turn-on", "turn-off"):
        return knob(ctx, args[0], on=operator == "turn-on")
    raise KeyError(f"no controller runs ({operator} {' '.join(args)})")


def holding_ok(ctx: Context, percept: LiberoPercept, obj: str, start_z: float) -> bool:
    """A pick's effect, perceived: the object is held and came up with the hand."""
    return held(ctx.scene, percept, obj) and percept.position(obj)[2] > start_z + 0.04
