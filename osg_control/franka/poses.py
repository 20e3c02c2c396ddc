"""Poses and waypoint helpers shared by the FrankaKitchen-v1 domain's skill modules.

Poses are in the env's world frame (the robot base stands at (0, 0, 1.8)).
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from osg_control.domain.spec import MOVEMENT, Node, ScriptParams, SkillSpec, Waypoint

ACTION_BOUNDS = (0.04, 0.04, 0.04, 0.2, 0.2, 0.2, 1.0)
"""Per-step bound of each action component: 4 cm, 0.2 rad (per 80 ms step), gripper (see
``osg_control.franka.env``: the 2 cm of the core's own kitchen is too slow here)."""
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
    """A waypoint at a node's pose and gripper state."""
    return Waypoint(node.position, node.gripper, orientation=node.orientation, **kw)


def movement(
    name: str,
    start: Node,
    end: Node,
    start_facts: tuple[str, ...] = (),
    steps: int | None = None,
) -> SkillSpec:
    """A contact-free movement skill from ``start`` straight to ``end``, recorded in a world
    where ``start_facts`` hold (made by the adapter's set-ups: e.g. the microwave opened);
    Algorithm 1's budget ``steps`` (default ``MOVE_STEPS``)."""
    budget = steps or MOVE_STEPS
    return SkillSpec(
        name=name,
        kind=MOVEMENT,
        start=start.name,
        end=end.name,
        waypoints=(at(end, steps=budget),),
        preconditions=frozenset({"hand-empty"}),
        start_facts=frozenset(start_facts),
        script=SCRIPT,
        max_steps=budget + MOVE_MAX_STEPS - MOVE_STEPS,
        start_radius=MOVE_START_RADIUS,
        start_angle=MOVE_START_ANGLE,
    )


MOVE_STEPS = 45
"""Algorithm 1's budget for a movement: from home to the slide cabinet (0.68 m) takes 27
steps noise-free (the servos cover 60-80 % of a 4 cm command per step, and the joints'
2 rad/s binds on long moves). The one longer move sets its own."""
MOVE_MAX_STEPS = 60
MOVE_START_RADIUS = 0.04
MOVE_START_ANGLE = 0.1
"""Random starts of movements: within 4 cm and 0.1 rad of their start node (a skill ends
within its 3 cm tolerance of its end node)."""


def grasp_pull_release(
    name: str,
    nodes: tuple[Node, Node, Node, Node],
    grasp: Waypoint,
    arc: tuple[Waypoint, ...],
    release: Waypoint,
    closed_fact: str,
    open_fact: str,
) -> tuple[SkillSpec, SkillSpec, SkillSpec]:
    """A handle's door as three skills, split where the gripper changes (as the core
    kitchen's grab-handle / slide-door-open / release-handle): ``grasp-NAME`` (front ->
    handle, closing at the end), ``pull-NAME`` (handle -> pulled along ``arc``, closed
    throughout), ``release-NAME`` (pulled -> opened: open, back off). Algorithm 1 switches
    the gripper in a single step, so a policy that had to learn a close or an open in the
    middle of a skill would average it away; at a skill's end it is what the reward asks.

    ``nodes``: (front, handle, pulled, opened).
    """
    front, handle, pulled, opened = nodes
    return (
        SkillSpec(
            name=f"grasp-{name}",
            kind="grasp",
            start=front.name,
            end=handle.name,
            waypoints=(grasp,),
            preconditions=frozenset({"hand-empty", closed_fact}),
            add_effects=frozenset({"holding"}),
            del_effects=frozenset({"hand-empty"}),
            max_steps=40,
            script=SCRIPT,
            success_tolerance=0.03,
        ),
        SkillSpec(
            name=f"pull-{name}",
            kind="pull",
            start=handle.name,
            end=pulled.name,
            waypoints=arc,
            preconditions=frozenset({"holding", closed_fact}),
            add_effects=frozenset({open_fact}),
            del_effects=frozenset({closed_fact}),
            start_facts=frozenset({"holding"}),
            max_steps=60,
            script=SCRIPT,
            success_tolerance=0.03,
            start_radius=0.0,
            start_angle=0.0,
        ),
        SkillSpec(
            name=f"release-{name}",
            kind="release",
            start=pulled.name,
            end=opened.name,
            waypoints=(release, at(opened, steps=8)),
            preconditions=frozenset({"holding", open_fact}),
            add_effects=frozenset({"hand-empty"}),
            del_effects=frozenset({"holding"}),
            start_facts=frozenset({"holding", open_fact}),
            max_steps=30,
            script=SCRIPT,
            success_tolerance=0.03,
            start_radius=0.0,
            start_angle=0.0,
        ),
    )
