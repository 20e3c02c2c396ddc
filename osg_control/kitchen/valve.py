"""The valve: where it stands, the push geometry of its skills, its nodes, and its place
as a ``world`` reset option (numpy only, no MuJoCo).

The valve is ``robots/kitchen.xml``'s body ``valve``: a knob on a vertical hinge with a
lever along its +x. Its place in the file is ``VALVE_HINGE``; the ``valve_pos`` reset
option moves the body to another (x, y) within ``VALVE_SHIFT`` of it for one episode
(``KitchenEnv.place_world``), the file's place otherwise. The world vector reads its place
(``world.VALVE_FIELDS``, a ``FIXTURE`` sensor) and its nodes are anchored to it
(``VALVE``), so its skills act in its frame wherever it stands.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from osg_control.domain.spec import Node, ObjectFrame
from osg_control.environment.options import finite_option
from osg_control.errors import EnvOptionError
from osg_control.perception.sensors import FIXTURE

VALVE_HINGE = (0.35, -0.45)
"""The valve's hinge axis (x, y) [m] in the file: a vertical axis through the knob's
centre (``robots/kitchen.xml``'s body ``valve``)."""
VALVE_BODY_Z = 0.03
"""Height of the valve body's origin [m] (the knob's centre; the file's)."""
VALVE_SHIFT = 0.04
"""How far [m] the ``valve_pos`` option may move the hinge from ``VALVE_HINGE`` along x
and along y: the valve's footprint (``VALVE_FOOTPRINT``) then stays 4.75 cm clear of the
cube's counter square (y <= -0.30 m, edge -0.3225 m) and far from the cabinet's plinth
(x >= 0.50 m, y >= 0.08 m), and the push's arc stays on the counter."""
VALVE_FOOTPRINT = ((-0.04, -0.04), (0.09, 0.04))
"""The valve's footprint on the counter relative to its hinge (x, y) [m]: the knob's 4 cm
radius and the lever's 9 cm reach along +x (the lever turns away from the cube, to -y)."""
VALVE_PUSH_Z = 0.07
"""TCP height [m] of the valve push: the fingertip pads (TCP z +- 9 mm) overlap the lever
(z 0.06-0.08) and stay above the counter; below the knob's top (0.06) only outside its rim."""
VALVE_PUSH_RADIUS = 0.075
"""Distance [m] from the hinge at which the +y finger pushes the lever: beyond the knob's rim
(4 cm, plus the pad's 9 mm half-width) and short of the lever's tip (9 cm)."""
VALVE_PUSH_ANGLES = (-0.35, -0.70, -1.05)
"""Lever angles [rad] of the push's arc waypoints: clockwise (the lever swings to -y, away
from the cube, the cabinet and every other skill's path) to about 1 rad."""
PUSH_FINGER_TRAVEL = 0.04
"""The open finger's inner face's distance from the TCP [m] the push point is laid out for:
the Panda's. The nodes are one graph for every robot, so a gripper that opens wider (the
UR5's 2F-85-like 0.0425 m) meets the lever that much deeper along the push (2.5 mm: the
push's arc tolerates it; ``tests/test_ur5_kitchen.py`` turns the valve with it)."""


def valve_push_point(angle: float) -> tuple[float, float, float]:
    """The TCP position [m] that puts the +y finger's inner face (``PUSH_FINGER_TRAVEL``
    from the TCP along y) on the lever's +y face (1 cm off its axis) at
    ``VALVE_PUSH_RADIUS`` when the lever is at ``angle`` [rad] about z (the valve at its
    file place)."""
    c, s = np.cos(angle), np.sin(angle)
    x = VALVE_HINGE[0] + VALVE_PUSH_RADIUS * c - 0.01 * s
    y = VALVE_HINGE[1] + VALVE_PUSH_RADIUS * s + 0.01 * c - PUSH_FINGER_TRAVEL
    return (round(float(x), 4), round(float(y), 4), VALVE_PUSH_Z)


VALVE_FIELDS: tuple[str, ...] = ("valve_x", "valve_y")
"""The world fields of the valve body's place (x, y) [m]: the world vector's last fields,
whatever the cubes (``world.world_fields``)."""
VALVE = ObjectFrame(
    name="valve",
    position_fields=VALVE_FIELDS,
    nominal=VALVE_HINGE,
    rest_z=VALVE_BODY_Z,
    region_low=(VALVE_HINGE[0] - VALVE_SHIFT, VALVE_HINGE[1] - VALVE_SHIFT),
    region_high=(VALVE_HINGE[0] + VALVE_SHIFT, VALVE_HINGE[1] + VALVE_SHIFT),
    evaluation_only=True,
)
"""The valve, located by its hinge's place (the world fields ``valve_x``, ``valve_y``): its
nodes move with it. ``--randomize-objects`` places it in the ``VALVE_SHIFT`` square around
its file place (the ``valve_pos`` option's region); Algorithm 1 leaves it at the file's
place (``evaluation_only``: the skills' data and every other draw stay as collected)."""
VALVE_SENSORS: dict[str, str] = dict.fromkeys(VALVE_FIELDS, FIXTURE)
"""The sensors of the valve's place: the pose estimator's position noise, drawn from its
own stream (the other fields' draws are those of a world vector without them)."""
VALVE_NODES: tuple[Node, ...] = (
    Node("above-valve", (VALVE_HINGE[0] + VALVE_PUSH_RADIUS, VALVE_HINGE[1], 0.25), anchor="valve"),
    Node(
        "valve-lever",
        (VALVE_HINGE[0] + VALVE_PUSH_RADIUS, VALVE_HINGE[1], VALVE_PUSH_Z),
        anchor="valve",
    ),
    Node("valve-pushed", valve_push_point(VALVE_PUSH_ANGLES[-1]), anchor="valve"),
)
"""The valve skills' nodes, given for the valve at its file place (``VALVE.nominal``) and
anchored to it: above the lever, at the lever, and at the end of the push."""


def valve_position(world: dict[str, Any]) -> np.ndarray:
    """The valve body's position [m] a ``world`` option dict puts it at: its ``valve_pos``
    (x, y), else the file's place (unchecked: ``check_valve_option`` checks)."""
    pos = world.get("valve_pos")
    x, y = VALVE_HINGE if pos is None else pos
    return np.array([float(x), float(y), VALVE_BODY_Z])


def check_valve_option(world: dict[str, Any]) -> None:
    """Refuse a ``valve_pos`` that is not two finite numbers within ``VALVE_SHIFT`` of the
    file's place along x and y.

    Raises:
        EnvOptionError: naming the option, its value and the allowed region.
    """
    if world.get("valve_pos") is None:
        return
    pos = finite_option("world.valve_pos", world["valve_pos"], (2,))
    shift = np.abs(pos - np.asarray(VALVE_HINGE))
    if np.any(shift > VALVE_SHIFT + 1e-12):
        low = [round(v - VALVE_SHIFT, 4) for v in VALVE_HINGE]
        high = [round(v + VALVE_SHIFT, 4) for v in VALVE_HINGE]
        raise EnvOptionError(
            f"reset option world.valve_pos {pos.tolist()} lies outside the valve's region "
            f"x in [{low[0]}, {high[0]}], y in [{low[1]}, {high[1]}] m (its file place "
            f"{list(VALVE_HINGE)} +- {VALVE_SHIFT} m, clear of the cube's square)"
        )


def valve_footprint(world: dict[str, Any]) -> tuple[tuple[float, float], tuple[float, float]]:
    """The valve's footprint (low and high x, y corners) [m] where ``world`` places it."""
    x, y, _z = valve_position(world)
    (lx, ly), (hx, hy) = VALVE_FOOTPRINT
    return (round(x + lx, 6), round(y + ly, 6)), (round(x + hx, 6), round(y + hy, 6))
