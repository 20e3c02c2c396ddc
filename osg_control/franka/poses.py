"""Poses and waypoint helpers shared by the FrankaKitchen-v1 domain's skill modules.

Poses are in the env's world frame (the robot base stands at (0, 0, 1.8)).
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from osg_control.domain.spec import MOVEMENT, Node, ScriptParams, SkillSpec, Waypoint

FORWARD = (0.5, -0.5, -0.5, -0.5)
"""Tool z along +y, fingers opening along world x: the orientation at the env's reset."""
HOME = Node("home", (-0.432, 0.119, 2.025), "open", FORWARD)
"""The TCP at the env's reset: every subtask's movement skills start or end here."""


def turned(
    axis: tuple[float, float, float],
    angle: float,
    base: tuple[float, float, float, float] = FORWARD,
) -> tuple[float, float, float, float]:
    """``base`` (default ``FORWARD``) turned by ``angle`` [rad] about the world ``axis``
    (a unit vector)."""
    turn, q = np.zeros(4), np.zeros(4)
    mujoco.mju_axisAngle2Quat(turn, np.asarray(axis, dtype=float), angle)
    mujoco.mju_mulQuat(q, turn, np.asarray(base, dtype=float))
    return tuple(round(float(v), 6) for v in q)  # type: ignore[return-value]


def wp(position: tuple[float, float, float], gripper: str, **kw: Any) -> Waypoint:
    """A waypoint with the tool ``FORWARD`` unless ``orientation`` is given."""
    return Waypoint(position, gripper, orientation=kw.pop("orientation", FORWARD), **kw)  # type: ignore[arg-type]


SCRIPT = ScriptParams(threshold_mean=0.01, threshold_std=0.003, noise_std=0.005)
"""Algorithm 1 parameters shared by the skills unless tuned per skill."""


def at(node: Node, **kw: Any) -> Waypoint:
    """A waypoint at ``node``'s pose and gripper state."""
    return Waypoint(node.position, node.gripper, orientation=node.orientation, **kw)


def movement(name: str, start: str, end: Node, steps: int = 25) -> SkillSpec:
    """A contact-free move, the hand empty, from the node named ``start`` to ``end`` in a
    budget of ``steps`` (a learned policy gets 15 more)."""
    return SkillSpec(
        name=name,
        kind=MOVEMENT,
        start=start,
        end=end.name,
        waypoints=(at(end, steps=steps),),
        preconditions=frozenset({"hand-empty"}),
        script=SCRIPT,
        max_steps=steps + 15,
    )
