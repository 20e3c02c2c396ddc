"""Whether a robot, where a domain mounts it, reaches the domain's nodes and skill waypoints.

Checked when a domain is built around another robot than its own (``Domain.with_robot``),
before any episode: each node is reached from the robot's home posture, then each skill's
waypoints in turn from its start node's configuration, along straight lines at the
domain's per-step position bound, by the differential IK of ``control.reach`` (mink, joint
position and velocity limits) on the robot's mounted arm-only model. Kinematics only: no
physics, no obstacles. A pose counts as reached within ``POSITION_TOL`` and
``ORIENTATION_TOL``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.control.reach import reach_pose
from osg_control.control.robot_model import arm_model
from osg_control.domain.spec import TOP_DOWN_QUAT
from osg_control.errors import DomainError

if TYPE_CHECKING:
    from osg_control.domain.base import Domain

POSITION_TOL = 0.01
"""How close [m] the TCP must come to a node or waypoint."""
ORIENTATION_TOL = 0.05
"""How close [rad] the TCP's orientation must come to a node's or waypoint's."""
STEPS = 400
"""IK steps (of 50 ms) allowed per pose."""


class UnreachableError(DomainError):
    """A robot, at its mount, does not reach a domain's node or skill waypoint."""


def unreachable(domain: Domain, robot: RobotDescription) -> list[str]:
    """Every node and skill waypoint ``robot`` does not reach, with its error (module
    docstring); empty when it reaches them all."""
    arm = arm_model(robot)
    limits = dict(zip(robot.arm.names, robot.arm.velocity, strict=True))
    max_step = domain.action_bounds[0]
    tol = (POSITION_TOL, ORIENTATION_TOL)

    def reach(position, quat, start):  # type: ignore[no-untyped-def]
        return reach_pose(
            arm, robot.tcp.site, position, quat, start, limits, STEPS,
            max_step=max_step, stop_within=tol,
        )  # fmt: skip

    missed = []
    home = reach(domain.nodes[domain.home].position, domain.nodes[domain.home].orientation,
                 np.array(robot.home_q))  # fmt: skip
    node_q = {domain.home: home.q}
    for name, node in domain.nodes.items():
        result = home if name == domain.home else reach(node.position, node.orientation, home.q)
        node_q[name] = result.q
        if not result.reached(*tol):
            missed.append(f"node {name!r} {node.position}: {result.position_error:.3f} m short")
    for skill in domain.skills:
        q = node_q[skill.start]
        for index, waypoint in enumerate(skill.waypoints):
            result = reach(waypoint.position, waypoint.orientation or TOP_DOWN_QUAT, q)
            q = result.q
            if not result.reached(*tol):
                missed.append(
                    f"skill {skill.name!r} waypoint {index} {waypoint.position}: "
                    f"{result.position_error:.3f} m short"
                )
    return missed


def check_reach(domain: Domain, robot: RobotDescription) -> None:
    """Refuse a robot that does not reach every node and skill waypoint of ``domain``.

    Raises:
        UnreachableError: naming the robot, its mount and what it misses.
    """
    missed = unreachable(domain, robot)
    if missed:
        raise UnreachableError(
            f"robot {robot.name!r} mounted at {robot.mount[0]} cannot reach what domain "
            f"{domain.name!r} needs (within {POSITION_TOL} m, {ORIENTATION_TOL} rad): "
            + "; ".join(missed)
        )
