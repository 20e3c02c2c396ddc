"""The hinge cabinet: grasp the right door's handle and pull it open along the door's arc.

Geometry (the library's MJCF, ``item_assets/hingecabinet_chain.xml``, placed by
``kitchen_env_model.xml``; world frame): the cabinet hangs at z 2.4-2.8 with two doors that
open toward the robot. The right door (``hingerightdoor``, qpos 21) turns about world +z on
the hinge at ``HINGE_AXIS`` (-0.224, 0.71), range [0, 1.57] rad, joint damping 2 N m s/rad and
friction loss 2 N m (nothing springs it back). Its handle is a vertical bar (radius 2.2 cm,
z 2.44-2.76) at ``HANDLE_OFFSET`` from the hinge in the door's shut frame, i.e. at
(-0.526, 0.582), 0.328 m from the axis, held 8 cm in front of the door face by two brackets
at z 2.486 and 2.714 (radius 1.9 cm). The library counts the task done when
``norm(qpos[20:22] - (0, 1.45)) < 0.3``: the right door past about 1.15 rad, the left door
(qpos 20) left near 0.

Why the waypoints are where they are (measured, noise-free unless said):

- The handle is near the edge of the arm's reach. A first script (level tool, grasp at
  z 2.48, the hand turning with the door, as for the microwave) stalled at 0.29-0.35 rad:
  no joint at a limit, but joints 1 and 3 asked for 10-18 rad/s (a near-singular pose), so
  the whole-vector scaling of the action froze the TCP and it sagged. Turning the hand by
  half the door's angle opened the door to 1.19 rad noise-free, but with the tool level the
  5 mm noise of Algorithm 1 made the approach drift onto the bar (0-4 of 10 grasps).
- The tool is tilted up by ``HINGE_PITCH`` (wrist below the TCP): the start pose is better
  conditioned (smallest singular value of the TCP Jacobian 0.10-0.14 against 0.07 level),
  and the hand keeps that one orientation throughout: the bar turns between the closed
  fingers. Turning the tool toward the hinge at the start (so that the fingers would hold
  the bar by their normal force, not friction) puts joint 4 at its -0.4 limit: the start
  is out of reach.
- ``HINGE_Z`` is in the bar's free span between the brackets (the fingers are 2 cm thick);
  2.53-2.61 all worked (19-20 of 20 under noise), the slips were lowest high on the bar.
- The pull follows the handle's circle about the hinge (``handle_point``) in steps of
  0.2-0.25 rad to 1.4 rad; the grasp holds by friction (the pull is mostly along the
  fingers) and the door lags the TCP, reaching the library's 1.15 rad at about the 1.2 rad
  waypoint. At the 1.45 rad waypoint joint 6 reached its upper limit (2.11).
- Then the fingers open and the hand backs off ``HINGE_BACK_OFF`` along -y (the bar leaves
  the open fingers; the door, now almost along y, is on the bar's far side) to
  ``hinge-opened``.
"""

from __future__ import annotations

import numpy as np

from osg_control.domain.spec import Node, SkillSpec
from osg_control.franka.poses import HOME, at, grasp_pull_release, movement, turned, wp

HINGE_AXIS = (-0.224, 0.71)
"""The right door's hinge axis (world x, y) [m]; it turns about world +z."""
HANDLE_OFFSET = (-0.302, -0.128)
"""The handle bar's axis from the hinge [m] with the door shut."""
HINGE_Z = 2.58
"""Grasp height [m] on the bar (free between the brackets at z 2.505-2.695)."""
HINGE_PITCH = 0.3
"""The tool tilted up about world x [rad] (tool z from +y toward +z)."""
HINGE_QUAT = turned((1.0, 0.0, 0.0), HINGE_PITCH)
HINGE_FRONT = 0.06
"""The start node's distance in front of (-y of) the bar [m]."""
HINGE_BACK_OFF = 0.10
"""How far the open hand backs off along -y at the end [m]."""
HINGE_ARC = (0.25, 0.5, 0.75, 1.0, 1.2, 1.4)
"""Door angles [rad] of the pull's waypoints (the library's goal is 1.45, done past 1.15)."""
HINGE_ARC_STEPS = (7, 6, 6, 5, 5, 5)
"""Step budget of each arc waypoint."""


def handle_point(angle: float) -> tuple[float, float, float]:
    """The TCP on the handle bar, at ``HINGE_Z``, when the door is at ``angle`` [rad]."""
    c, s = float(np.cos(angle)), float(np.sin(angle))
    dx, dy = HANDLE_OFFSET
    return (
        round(HINGE_AXIS[0] + c * dx - s * dy, 4),
        round(HINGE_AXIS[1] + s * dx + c * dy, 4),
        HINGE_Z,
    )


def _shifted(point: tuple[float, float, float], dy: float) -> tuple[float, float, float]:
    """``point`` moved by ``dy`` along world y."""
    return (point[0], round(point[1] + dy, 4), point[2])


HINGE_NODES: tuple[Node, ...] = (
    Node("hinge-front", _shifted(handle_point(0.0), -HINGE_FRONT), "open", HINGE_QUAT),
    Node("hinge-handle", handle_point(0.0), "closed", HINGE_QUAT),
    Node("hinge-pulled", handle_point(HINGE_ARC[-1]), "closed", HINGE_QUAT),
    Node(
        "hinge-opened", _shifted(handle_point(HINGE_ARC[-1]), -HINGE_BACK_OFF), "open", HINGE_QUAT
    ),
)
"""The door's nodes: the open hand in front of the shut door's handle, the hand closed on
it, closed on it with the door pulled open, and the open hand backed off."""

HINGE_SKILLS: tuple[SkillSpec, ...] = (
    movement("move-home-to-hinge", HOME, HINGE_NODES[0]),
    movement("move-hinge-to-home", HINGE_NODES[-1], HOME, ("hinge-open",)),
    *grasp_pull_release(
        "hinge",
        HINGE_NODES,  # type: ignore[arg-type]
        at(HINGE_NODES[1], steps=12, reach=0.012),
        tuple(
            wp(handle_point(a), "closed", steps=n, reach=0.02, orientation=HINGE_QUAT)
            for a, n in zip(HINGE_ARC, HINGE_ARC_STEPS, strict=True)
        ),
        wp(handle_point(HINGE_ARC[-1]), "open", steps=3, reach=0.05, orientation=HINGE_QUAT),
        "hinge-closed",
        "hinge-open",
    ),
)
"""The movements between home and the hinge nodes, and the door's grasp, pull (along the
door's arc) and release (let go, back off)."""
