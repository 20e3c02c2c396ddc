"""Controllers for LIBERO's fixtures, from the scene's joints and the sensed joint angles:
a drawer opened by pulling its handle (pinched top and bottom by the hand held level in
front of it) or closed by pushing its front, a door closed by pushing its leaf round the
hinge, a knob grasped across its grip and turned with the wrist.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.drive import GRIPPER_CLOSED, GRIPPER_OPEN
from osg_control.libero.facts import handle_at
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
KNOB_STEP = 0.1
"""How far ahead of the sensed knob angle the wrist is turned each step [rad]: further
ahead, the IK gave up the grasp point for the turn (the knob is heavy) and the fingers
slipped off."""
KNOB_PITCH = np.radians(30.0)
"""How far the hand grasping a knob is tilted, its fingertips toward the arm's base: a
knob next to the base (LIBERO-Goal's stove) is then reached at its grasp height; top-down,
the elbow folded to its limit 2 cm above it."""
PUSH_PITCH = np.radians(35.0)
"""How far the hand pushing a drawer shut is tilted toward the cabinet (``pitched``)."""
DRAWER_MARGIN = 0.02
"""How far past LIBERO's open threshold a drawer is pulled [m]."""
PINCH_REACH = 0.006
"""How near the TCP goes in to a point this far behind a drawer's handle before pinching
it [m]: it then stops at the handle's bar, not this far in front of it (there, with the
sensed travel 4 mm short, the fingers closed 1 cm in front of the bar's centre and the
pull left LIBERO-Goal's middle drawer shut, task 0 state 3)."""
PULL_STANDOFF = 0.12
"""How far in front of a drawer's handle the hand hovers and turns level before it goes
in [m]: the top-down hand, its long side along the drawer's travel, stays clear of the
handles of the drawers above."""


def pitched(rotation: np.ndarray, toward: np.ndarray, angle: float = PUSH_PITCH) -> np.ndarray:
    """``rotation`` with its approach axis (the TCP's z, down) tilted ``angle`` toward
    ``toward``, about the fingers' axis: the wrist and forearm then stay back and up, clear
    of a cabinet's top while the fingertips push its bottom drawer (or of a microwave's
    roof while they push a mug into it, ``insert``)."""
    tilts = [Rotation.from_rotvec(rotation[:, 1] * a).as_matrix() @ rotation
             for a in (angle, -angle)]  # fmt: skip
    return max(tilts, key=lambda r: float(r[:, 2] @ toward))


def _level(rotation: np.ndarray, out: np.ndarray) -> np.ndarray:
    """The top-down ``rotation`` (its fingers sliding along ``out``) tilted a quarter turn
    about its x axis so that it faces ``-out``: the hand level, pointing into the drawer,
    its fingers sliding vertically (they close on the handle's bar from above and below;
    from above, the handles of the drawers higher up are in the way)."""
    tilts = [Rotation.from_rotvec(rotation[:, 0] * a).as_matrix() @ rotation
             for a in (np.pi / 2, -np.pi / 2)]  # fmt: skip
    return max(tilts, key=lambda r: float(r[:, 2] @ -out))


def drawer_front(ctx: Context, percept: LiberoPercept, region: str) -> np.ndarray:
    """The point ``PULL_STANDOFF`` in front of a drawer's handle at its sensed travel: where
    the empty hand approaches a drawer (``pick_place.approach``, ``HOVER`` above it)."""
    joint = ctx.scene.joints[ctx.scene.articulated[region][0]]
    out = joint.outward
    return handle_at(ctx.scene, joint, percept.joint(joint.name)) + out * PULL_STANDOFF


def drawer_hand(ctx: Context, region: str) -> np.ndarray:
    """The hand the empty hand approaches a drawer with: turned level for the pull
    (``_level``) when the plan opens it next (``Context.opening``: turned in place, at the
    careful pace, it took 31-40 of LIBERO-Goal task 3's 300 steps), else the start's."""
    if region not in ctx.opening:
        return ctx.base
    return _pull_hand(ctx, ctx.scene.joints[ctx.scene.articulated[region][0]])


def _pull_hand(ctx: Context, joint: Joint) -> np.ndarray:
    """The hand that pinches a drawer's handle: level, facing the drawer (``_level``)."""
    out = joint.outward
    return _level(fingers_along(ctx, out), out)


def drawer(ctx: Context, region: str, opening: bool) -> list[Leg]:
    """Open: grasp the handle, pull past the open threshold. Close: push the handle's
    face with the closed hand to the closed stop."""
    joint = ctx.scene.joints[ctx.scene.articulated[region][0]]
    out = joint.outward  # the direction the drawer comes out
    across = fingers_along(ctx, np.cross(out, [0.0, 0.0, 1.0]))  # the hand thin along out
    sensed = lambda p: p.joint(joint.name)  # noqa: E731
    if opening:  # pinch the handle's bar top and bottom, the hand level, facing the drawer
        goal = joint.active + joint.opening * DRAWER_MARGIN
        level = _pull_hand(ctx, joint)
        return [
            Leg(lambda now, s: (drawer_front(ctx, s, region) + [0, 0, HOVER], level),
                GRIPPER_OPEN, 40, 0.02, transit=True),
            Leg(lambda now, s: (drawer_front(ctx, s, region), level), GRIPPER_OPEN, 40, 0.01,
                transit=True),
            Leg(lambda now, s: (handle_at(ctx.scene, joint, sensed(s)) - out * PINCH_REACH, level),
                GRIPPER_OPEN, 40, PINCH_REACH),
            hold(GRIPPER_CLOSED, 12),
            Leg(lambda now, s: (handle_at(ctx.scene, joint, goal), level), GRIPPER_CLOSED, 60,
                0.01, lambda p: joint.is_active(sensed(p) - joint.opening * DRAWER_MARGIN)),
            hold(GRIPPER_OPEN, 8),
            Leg(here(tuple(out * PUSH_STANDOFF)), GRIPPER_OPEN, 20, 0.02),
        ]  # fmt: skip
    shut = joint.shut
    across = pitched(across, -out)
    front = lambda now, q: handle_at(ctx.scene, joint, q) + out * PUSH_STANDOFF  # noqa: E731
    return [
        Leg(lambda now, s: (front(now, sensed(s)) + [0, 0, HOVER], across), GRIPPER_CLOSED,
            40, 0.02, transit=True),
        Leg(lambda now, s: (front(now, sensed(s)), across), GRIPPER_CLOSED, 30, 0.015),
        Leg(lambda now, s: (handle_at(ctx.scene, joint, shut) - out * 0.03, across),
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
    """Grasp the knob across its grip (``scene.Scene.grips``), the hand tilted
    ``KNOB_PITCH``, turn the wrist about the knob's axis (at most ``KNOB_STEP`` ahead of
    where it is) until the sensed angle is ``KNOB_TURN`` past LIBERO's threshold, let go,
    up."""
    joint = ctx.scene.joints[ctx.scene.articulated[fixture][0]]
    point = ctx.scene.knobs[fixture]
    sign = joint.opening if on else -joint.opening
    goal = (joint.active if on else joint.rest) + sign * KNOB_TURN
    grasp = pitched(fingers_along(ctx, ctx.scene.grips[fixture]), ctx.base_xy - point,
                    KNOB_PITCH)  # fmt: skip

    def turn(now: LiberoPercept, start: LiberoPercept) -> tuple[np.ndarray, np.ndarray]:
        step = float(np.clip(goal - now.joint(joint.name), -KNOB_STEP, KNOB_STEP))
        _, rot = ctx.driver.tcp_pose(now.joints)
        return point, Rotation.from_rotvec(joint.axis * step).as_matrix() @ rot

    def done(p: LiberoPercept) -> bool:
        return bool((p.joint(joint.name) - goal) * sign > 0)

    return [
        Leg(lambda now, s: (point + [0, 0, HOVER], grasp), GRIPPER_OPEN, 40, 0.02),
        Leg(lambda now, s: (point, grasp), GRIPPER_OPEN, 30, 0.006),
        hold(GRIPPER_CLOSED, 12),
        Leg(turn, GRIPPER_CLOSED, 60, 0.0, done),
        hold(GRIPPER_OPEN, 8),
        up(HOVER, GRIPPER_OPEN),
    ]
