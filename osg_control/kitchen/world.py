"""The kitchen's world state beyond the robot and its PDDL facts (numpy only, no MuJoCo).

``WorldState`` is what the scene reads (door travel, valve angle, cube pose, which objects
both fingers touch); ``world_facts`` abstracts it into the kitchen's facts; the flat vector
``WORLD_FIELDS`` is how data sets store it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
class WorldState:
    """What the simulator knows beyond the robot's 10-D state (never fed to policies).

    Attributes:
        door_opening: door travel along its slide [m] (0 = shut).
        valve_angle: valve knob angle [rad].
        cube_pos: cube centre [m] in the kitchen's world frame.
        cube_quat: cube orientation, ``w, x, y, z``.
        cube_grasped: both fingers touch the cube.
        handle_grasped: both fingers touch the door handle.
    """

    door_opening: float
    valve_angle: float
    cube_pos: tuple[float, float, float]
    cube_quat: tuple[float, float, float, float]
    cube_grasped: bool
    handle_grasped: bool

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
        """The cube rests in the cabinet: its centre inside the interior box, not grasped."""
        (x, y, z), ((lx, hx), (ly, hy), (lz, hz)) = self.cube_pos, _CABINET_BOUNDS
        return lx < x < hx and ly < y < hy and lz < z < hz and not self.cube_grasped

    @property
    def cube_on_counter(self) -> bool:
        """The cube rests on the counter (not lifted, not in the cabinet)."""
        return self.cube_pos[2] < CUBE_HALF_SIZE + COUNTER_REST_MARGIN and not self.cube_in_cabinet

    @property
    def cube_lifted(self) -> bool:
        """The cube is held clear of every surface (5 cm above the counter or more)."""
        return self.cube_grasped and self.cube_pos[2] > CUBE_HALF_SIZE + 0.05

    def as_array(self) -> np.ndarray:
        """Flat float vector (see ``WORLD_FIELDS``) for storage in data sets."""
        return np.array(
            [
                self.door_opening,
                self.valve_angle,
                *self.cube_pos,
                *self.cube_quat,
                float(self.cube_grasped),
                float(self.handle_grasped),
            ]
        )


def world_facts(world: WorldState) -> frozenset[str]:
    """Abstract a world state into the kitchen's PDDL facts (``skills.WORLD_FACTS``).

    Args:
        world: the simulator's world state.

    Returns:
        The facts that hold; hand-empty means neither the cube nor the handle is grasped.
    """
    named = (
        ("door-open" if world.door_open else "door-closed", True),
        ("valve-open" if world.valve_open else "valve-closed", True),
        ("cube-in-cabinet", world.cube_in_cabinet),
        ("cube-on-counter", world.cube_on_counter),
        ("cube-lifted", world.cube_lifted),
        ("holding-cube", world.cube_grasped),
        ("holding-handle", world.handle_grasped),
        ("hand-empty", not (world.cube_grasped or world.handle_grasped)),
    )
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


def world_state_from_array(values: np.ndarray) -> WorldState:
    """Inverse of ``WorldState.as_array``."""
    v = np.asarray(values, dtype=float).tolist()  # Python floats: read every step
    return WorldState(
        door_opening=v[0],
        valve_angle=v[1],
        cube_pos=(v[2], v[3], v[4]),
        cube_quat=(v[5], v[6], v[7], v[8]),
        cube_grasped=v[9] > 0.5,
        handle_grasped=v[10] > 0.5,
    )
