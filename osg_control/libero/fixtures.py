"""Controllers for LIBERO's fixtures, from the scene's joints and the sensed joint angles:
a drawer opened by pulling its handle or closed by pushing its front, a door closed by
pushing its leaf round the hinge, a knob turned with the wrist.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.drive import GRIPPER_CLOSED, GRIPPER_OPEN
from osg_control.libero.grasp import fingers_along
from osg_control.libero.legs import HOVER, Context, Leg, here, hold, up
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.scene import Joint

PUSH_STANDOFF = 0.05
"""Distance from a drawer's handle or a door's leaf the pushing hand starts at [m]."""
DOOR_STANDOFF = 0.045
"""Distance from a door's leaf the pushing hand comes down at [m]: robosuite's Panda hand
is 3.2 cm thick either side of the TCP (at 2.5 cm it came down on the leaf's top edge of
a door opened past a right angle, LIBERO-10 task 9 state 4)."""
DOOR_PUSH_STANDOFF = 0.02
"""The same while it pushes [m]: at the closed stop the hand's face is then past the shut
leaf's plane (at 4.5 cm it stopped 1.3 cm short of it, and a slow push left the door open
past LIBERO's 0.005 rad threshold, state 35)."""
DOOR_LEAD = 0.35
"""How far ahead of the sensed door angle the push point is put [rad]."""
DOOR_RADIUS = 0.6
"""Where a door is pushed, as a fraction of the leaf's length from the hinge."""
KNOB_TURN = 0.4
"""How far past LIBERO's threshold a knob is turned [rad]."""
PUSH_PITCH = np.radians(35.0)
"""How far the hand pushing a drawer shut is tilted toward the cabinet (``pitched``)."""
DRAWER_MARGIN = 0.02
"""How far past LIBERO's open threshold a drawer is pulled [m]."""


def pitched(rotation: np.ndarray, toward: np.ndarray, angle: float = PUSH_PITCH) -> np.ndarray:
    """``rotation`` with its approach axis (the TCP's z, down) tilted ``angle`` toward
    ``toward``, about the fingers' axis: the wrist and forearm then stay back and up, clear
    of a cabinet's top while the fingertips push its bottom drawer (or of a microwave's
    roof while they push a mug into it, ``insert``)."""
    tilts = [Rotation.from_rotvec(rotation[:, 1] * a).as_matrix() @ rotation
             for a in (angle, -angle)]  # fmt: skip
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
            Leg(here(tuple(out * PUSH_STANDOFF)), GRIPPER_OPEN, 20, 0.02),
        ]  # fmt: skip
    shut = joint.shut
    across = pitched(across, -out)
    front = lambda now, q: _handle(ctx, now, joint, q) + out * PUSH_STANDOFF  # noqa: E731
    return [
        Leg(lambda now, s: (front(now, sensed(s)) + [0, 0, HOVER], across), GRIPPER_CLOSED,
            40, 0.02),
        Leg(lambda now, s: (front(now, sensed(s)), across), GRIPPER_CLOSED, 30, 0.015),
        Leg(lambda now, s: (_handle(ctx, now, joint, shut) - out * 0.03, across),
            GRIPPER_CLOSED, 60, 0.035),
        Leg(here(tuple(out * PUSH_STANDOFF)), GRIPPER_CLOSED, 20, 0.02),
    ]  # fmt: skip


def door_point(
    ctx: Context, percept: LiberoPercept, door: str, joint: Joint, q: float,
    standoff: float = DOOR_STANDOFF,
) -> np.ndarray:  # fmt: skip
    """The push point on the door's closing side when the door is at ``q``, standing off
    ``standoff`` from the leaf."""
    tip = ctx.scene.leaves[door]
    turn = Rotation.from_rotvec(joint.axis * (q - joint.q0)).as_matrix()
    radial = turn @ (tip - joint.anchor)
    radial -= (radial @ joint.axis) * joint.axis
    closing = np.cross(joint.axis, radial / np.linalg.norm(radial)) * -joint.opening
    point = joint.anchor + DOOR_RADIUS * radial - closing * standoff
    return np.r_[point[:2], joint.anchor[2]]


def door(ctx: Context, fixture: str) -> list[Leg]:
    """Close a door: from beside the leaf, push the point ``DOOR_LEAD`` ahead of the
    sensed angle round the hinge, up to the closed stop."""
    joint = ctx.scene.joints[ctx.scene.articulated[fixture][0]]
    shut = joint.shut

    def ahead(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, None]:
        q = now.joint(joint.name) - joint.opening * DOOR_LEAD
        q = min(q, shut) if joint.opening < 0 else max(q, shut)
        return door_point(ctx, now, fixture, joint, q, DOOR_PUSH_STANDOFF), None

    at = lambda now, s: door_point(ctx, now, fixture, joint, s.joint(joint.name))  # noqa: E731
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
