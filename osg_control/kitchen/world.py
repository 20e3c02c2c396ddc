"""The kitchen's world state beyond the robot and its PDDL facts (numpy only, no MuJoCo).

``WorldState`` is what the scene reads (door travel, valve angle, each cube's pose, which
objects both fingers touch); ``world_facts`` abstracts it into the kitchen's facts; the flat
vector ``world_fields(cubes)`` is how data sets store it: the one-cube layout
``WORLD_FIELDS`` (11 values), then 8 values per further cube (``cube2_x`` ...), then the
valve's place (``VALVE_FIELDS``). A vector stored before the valve's place was a field
(11 + 8 per further cube) still reads: its valve stood at the file's place.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from osg_control.kitchen.objects import HAND_EMPTY_FACT, MAX_CUBES, cube_fact, cube_prefix
from osg_control.kitchen.valve import VALVE_FIELDS, VALVE_HINGE

CUBE_HALF_SIZE = 0.0225
"""Half the cube's edge [m]."""
CABINET_INTERIOR_LOW = np.array([0.52, 0.10, 0.07])
CABINET_INTERIOR_HIGH = np.array([0.84, 0.56, 0.70])
"""Axis-aligned bounds of the cabinet's interior [m], world frame; the floor's top is at
0.10 m, the low bound 3 cm under it so that a resting cube (centre 0.1225 m) seen through
the robot perception's 1 cm pose noise stays inside (a counter cube, 0.0225 m, stays out)."""
_CABINET_BOUNDS = tuple(
    zip(CABINET_INTERIOR_LOW.tolist(), CABINET_INTERIOR_HIGH.tolist(), strict=True)
)
"""(low, high) per axis as floats: compared several times every control step."""
COUNTER_REST_MARGIN = 0.03
"""How far above its resting height [m] the cube still counts on the counter: three times
the robot perception's 1 cm pose noise (a lifted cube is 5 cm up or more)."""
DOOR_OPEN_MIN = 0.30
"""Door travel [m] from which the door counts as open (the opening then clears the cube)."""
VALVE_OPEN_MIN = 0.5
"""Valve angle [rad], either way, from which the valve counts as open: the push skill
sweeps the lever about 1 rad, while touches by other skills move it by hundredths."""


@dataclass(frozen=True)
class CubeState:
    """One cube as the simulator knows it: centre [m], orientation (``w, x, y, z``), and
    whether both fingers touch it."""

    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float]
    grasped: bool

    @property
    def in_cabinet(self) -> bool:
        """The cube rests in the cabinet: its centre inside the interior box, not grasped."""
        (x, y, z), ((lx, hx), (ly, hy), (lz, hz)) = self.pos, _CABINET_BOUNDS
        return lx < x < hx and ly < y < hy and lz < z < hz and not self.grasped

    @property
    def on_counter(self) -> bool:
        """The cube rests on the counter (not lifted, not in the cabinet)."""
        return self.pos[2] < CUBE_HALF_SIZE + COUNTER_REST_MARGIN and not self.in_cabinet

    @property
    def lifted(self) -> bool:
        """The cube is held clear of every surface (5 cm above the counter or more)."""
        return self.grasped and self.pos[2] > CUBE_HALF_SIZE + 0.05

    def values(self) -> list[float]:
        """Its 8 world-vector values (``CUBE_FIELDS``)."""
        return [*self.pos, *self.quat, float(self.grasped)]


@dataclass(frozen=True)
class WorldState:
    """What the simulator knows beyond the robot's 10-D state (never fed to policies).

    Attributes:
        door_opening: door travel along its slide [m] (0 = shut).
        valve_angle: valve knob angle [rad].
        cube_pos: cube 1's centre [m] in the kitchen's world frame.
        cube_quat: cube 1's orientation, ``w, x, y, z``.
        cube_grasped: both fingers touch cube 1.
        handle_grasped: both fingers touch the door handle.
        more_cubes: cubes 2, 3, ... of a scene with more than one.
        valve_pos: the valve body's (x, y) [m] (the ``valve_pos`` reset option moves it).
    """

    door_opening: float
    valve_angle: float
    cube_pos: tuple[float, float, float]
    cube_quat: tuple[float, float, float, float]
    cube_grasped: bool
    handle_grasped: bool
    more_cubes: tuple[CubeState, ...] = ()
    valve_pos: tuple[float, float] = VALVE_HINGE

    @property
    def cubes(self) -> tuple[CubeState, ...]:
        """Every cube, cube 1 first."""
        return (CubeState(self.cube_pos, self.cube_quat, self.cube_grasped), *self.more_cubes)

    @property
    def door_open(self) -> bool:
        """The door has slid far enough to clear the cabinet's opening."""
        return self.door_opening >= DOOR_OPEN_MIN

    @property
    def valve_open(self) -> bool:
        """The valve has turned far enough from shut, either way."""
        return abs(self.valve_angle) >= VALVE_OPEN_MIN

    @property
    def cube_in_cabinet(self) -> bool:
        """Cube 1 rests in the cabinet (``CubeState.in_cabinet``)."""
        return self.cubes[0].in_cabinet

    @property
    def cube_on_counter(self) -> bool:
        """Cube 1 rests on the counter (``CubeState.on_counter``)."""
        return self.cubes[0].on_counter

    @property
    def cube_lifted(self) -> bool:
        """Cube 1 is held clear of every surface (``CubeState.lifted``)."""
        return self.cubes[0].lifted

    def as_array(self) -> np.ndarray:
        """Flat float vector (see ``world_fields``) for storage in data sets."""
        values = [
            self.door_opening,
            self.valve_angle,
            *self.cube_pos,
            *self.cube_quat,
            float(self.cube_grasped),
            float(self.handle_grasped),
        ]
        for cube in self.more_cubes:
            values += cube.values()
        return np.array([*values, *self.valve_pos])


def world_facts(world: WorldState) -> frozenset[str]:
    """Abstract a world state into the kitchen's PDDL facts (``objects.world_fact_names``).

    Args:
        world: the simulator's world state.

    Returns:
        The facts that hold: cube 1's by their names (``cube-on-counter``), cube k's as
        atoms (``(on-counter cube-2)``, ``objects.cube_fact``); hand-empty means no cube
        and not the handle is grasped.
    """
    named = [
        ("door-open" if world.door_open else "door-closed", True),
        ("valve-open" if world.valve_open else "valve-closed", True),
        ("holding-handle", world.handle_grasped),
    ]
    for k, cube in enumerate(world.cubes, 1):
        named += [
            (cube_fact("cube-in-cabinet", k), cube.in_cabinet),
            (cube_fact("cube-on-counter", k), cube.on_counter),
            (cube_fact("cube-lifted", k), cube.lifted),
            (cube_fact("holding-cube", k), cube.grasped),
        ]
    held = world.handle_grasped or any(cube.grasped for cube in world.cubes)
    named.append((HAND_EMPTY_FACT, not held))
    return frozenset([name for name, holds in named if holds])


WORLD_FIELDS: tuple[str, ...] = (
    "door_opening",
    "valve_angle",
    "cube_x",
    "cube_y",
    "cube_z",
    "cube_qw",
    "cube_qx",
    "cube_qy",
    "cube_qz",
    "cube_grasped",
    "handle_grasped",
)
"""The one-cube world vector's fields (cube 1's are ``cube_x`` ... ``cube_grasped``)."""
CUBE_FIELDS: tuple[str, ...] = ("x", "y", "z", "qw", "qx", "qy", "qz", "grasped")
"""Each cube's world fields after its prefix (``cube_`` for cube 1, ``cube2_`` ...)."""


def world_fields(cubes: int = 1) -> tuple[str, ...]:
    """The world vector's fields with ``cubes`` cubes: ``WORLD_FIELDS``, then each further
    cube's 8 (``cube2_x`` ... ``cube2_grasped``), then ``VALVE_FIELDS``."""
    more = (f"{cube_prefix(k)}_{f}" for k in range(2, cubes + 1) for f in CUBE_FIELDS)
    return WORLD_FIELDS + tuple(more) + VALVE_FIELDS


def cube_count(width: int) -> int:
    """How many cubes a world vector of ``width`` values holds: ``world_fields``'s width,
    or a vector stored before ``VALVE_FIELDS`` were fields (``has_valve_fields``).

    Raises:
        ValueError: a width that is no kitchen vector's.
    """
    extra, rest = divmod(width - len(WORLD_FIELDS), len(CUBE_FIELDS))
    if rest == len(VALVE_FIELDS):
        rest = 0
    if rest or not 0 <= extra < MAX_CUBES:
        raise ValueError(
            f"a kitchen world vector has {len(WORLD_FIELDS)} values plus {len(CUBE_FIELDS)} "
            f"per cube beyond the first (1 to {MAX_CUBES} cubes) plus the valve's "
            f"{len(VALVE_FIELDS)} (absent from vectors stored before them), got {width}"
        )
    return 1 + extra


def has_valve_fields(width: int) -> bool:
    """Whether a kitchen world vector of ``width`` values ends with ``VALVE_FIELDS`` (one
    stored before they were fields does not: its valve stood at the file's place)."""
    return (width - len(WORLD_FIELDS)) % len(CUBE_FIELDS) == len(VALVE_FIELDS)


def world_state_from_array(values: np.ndarray) -> WorldState:
    """Inverse of ``WorldState.as_array`` (any number of cubes, ``cube_count``; a vector
    without the valve's fields has it at the file's place, ``has_valve_fields``)."""
    v = np.asarray(values, dtype=float).tolist()  # Python floats: read every step
    n = len(WORLD_FIELDS)
    valve = VALVE_HINGE
    if len(v) != n:
        cube_count(len(v))
        if has_valve_fields(len(v)):
            valve = (v[-2], v[-1])
            v = v[:-2]
    more = tuple(
        CubeState((c[0], c[1], c[2]), (c[3], c[4], c[5], c[6]), c[7] > 0.5)
        for c in (v[i : i + len(CUBE_FIELDS)] for i in range(n, len(v), len(CUBE_FIELDS)))
    )
    return WorldState(
        door_opening=v[0],
        valve_angle=v[1],
        cube_pos=(v[2], v[3], v[4]),
        cube_quat=(v[5], v[6], v[7], v[8]),
        cube_grasped=v[9] > 0.5,
        handle_grasped=v[10] > 0.5,
        more_cubes=more,
        valve_pos=valve,
    )
