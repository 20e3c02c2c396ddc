"""Validation of the kitchen's ``world`` reset options (door travel, cube positions, the
valve's place).

A cube position must be one where the cube rests and the arm can reach it: on the counter's
top, clear of the cabinet's plinth and the valve (where ``valve_pos`` puts it), or on the
cabinet's floor, and within the robot's workspace (``robot_model.workspace``). The valve's
place is checked by ``valve.check_valve_option``. The scene's dimensions are
``robots/kitchen.xml``'s.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from osg_control.environment.options import Sphere, check_reach, finite_option
from osg_control.errors import EnvOptionError, PlacementError
from osg_control.kitchen.cubes import REST_PLACES
from osg_control.kitchen.objects import cube_prefix
from osg_control.kitchen.valve import check_valve_option, valve_footprint
from osg_control.kitchen.world import CABINET_INTERIOR_HIGH, CABINET_INTERIOR_LOW, CUBE_HALF_SIZE

DOOR_TRAVEL = 0.45
"""The door slide's range [m] (``robots/kitchen.xml``)."""
WORLD_OPTIONS = ("door_opening", "cube_pos", "valve_pos")
"""The kitchen's ``world`` reset options with one cube (``world_options``)."""


def cube_option(k: int) -> str:
    """The ``world`` reset option that places cube k: ``cube_pos``, ``cube2_pos`` ..."""
    return f"{cube_prefix(k)}_pos"


def world_options(cubes: int) -> tuple[str, ...]:
    """The ``world`` reset options with ``cubes`` cubes: each cube's position too."""
    return WORLD_OPTIONS + tuple(cube_option(k) for k in range(2, cubes + 1))


CUBE_RESTS = {
    "the counter": ((-0.35, -0.70, 0.0), (1.05, 0.90)),
    "the cabinet's floor": (
        (CABINET_INTERIOR_LOW[0], CABINET_INTERIOR_LOW[1], 0.10),
        (CABINET_INTERIOR_HIGH[0], CABINET_INTERIOR_HIGH[1]),
    ),
}
"""Where the cube may rest: each surface's lower corner (x, y, top z) and upper (x, y) [m]."""
COUNTER_OBSTACLES = {"the cabinet's plinth": ((0.50, 0.08), (0.86, 0.58))}
"""Fixed footprints (x, y) [m] on the counter's top that the cube would cut into (and the
valve's, ``valve.valve_footprint``, where the options place it)."""
REST_TOLERANCE = 0.005
"""How far [m] above its surface a cube position may lie (it settles in the start's 0.1 s)."""


def check_world_options(
    world: dict[str, Any], holding: str | None, reach: Sphere, cubes: int = 1
) -> None:
    """Refuse a non-finite or out-of-range door opening or cube position (outside the
    robot's workspace ``reach`` included), a cube position with the cube held, or two of
    ``cubes`` cubes overlapping where the options and the scene's rest places put them.

    Raises:
        EnvOptionError: naming the option and its value.
        PlacementError: naming the two overlapping cubes and their places.
    """
    check_valve_option(world)
    door = float(finite_option("world.door_opening", world.get("door_opening", 0.0)))
    if not 0.0 <= door <= DOOR_TRAVEL:
        raise EnvOptionError(
            f"reset option world.door_opening must lie in [0, {DOOR_TRAVEL}] m, got {door}"
        )
    if world.get("cube_pos") is not None:
        if holding == "cube":
            raise EnvOptionError(
                "reset options contradict each other: world.cube_pos while holding 'cube' "
                "(a held cube is placed in the fingers)"
            )
        pos = finite_option("world.cube_pos", world["cube_pos"], (3,))
        check_cube_position(pos, reach, valve=valve_footprint(world))
    places = []
    for k in range(1, cubes + 1):
        option = cube_option(k)
        if world.get(option) is None:
            if k > 1 or holding != "cube":
                places.append((option, np.array([*REST_PLACES[k - 1], CUBE_HALF_SIZE])))
            continue
        if k > 1:
            pos = finite_option(f"world.{option}", world[option], (3,))
            check_cube_position(pos, reach, option, valve_footprint(world))
        places.append((option, np.asarray(world[option], dtype=float)))
    check_apart(places)


def check_apart(places: list[tuple[str, np.ndarray]]) -> None:
    """Refuse two cubes that overlap (their boxes, axis-aligned, intersect).

    Raises:
        PlacementError: naming both and where they are.
    """
    for i, (first, a) in enumerate(places):
        for second, b in places[i + 1 :]:
            if np.all(np.abs(a - b) < 2 * CUBE_HALF_SIZE):
                raise PlacementError(
                    f"reset options place two cubes overlapping: {first} at {a.tolist()} and "
                    f"{second} at {b.tolist()} (their centres must be at least "
                    f"{2 * CUBE_HALF_SIZE} m apart along x, y or z)"
                )


def check_cube_position(
    pos: np.ndarray,
    reach: Sphere,
    option: str = "cube_pos",
    valve: tuple[tuple[float, float], tuple[float, float]] | None = None,
) -> None:
    """Refuse a cube position (the ``world`` option ``option``) where it does not rest on
    a surface or out of reach (``valve``: the valve's footprint, default at its file
    place).

    Raises:
        EnvOptionError: naming the option, the value and the rule broken.
    """
    check_reach(f"world.{option}", pos, reach)
    where = f"reset option world.{option} {pos.tolist()}"
    surface = _resting_surface(pos)
    if surface is None:
        raise EnvOptionError(
            f"{where} does not rest on {' or '.join(CUBE_RESTS)} (its centre "
            f"{CUBE_HALF_SIZE} m above, within {REST_TOLERANCE} m, clear of the edges)"
        )
    if surface == "the counter":
        obstacles = {**COUNTER_OBSTACLES, "the valve": valve or valve_footprint({})}
        for obstacle, (low, high) in obstacles.items():
            if all(low[i] - CUBE_HALF_SIZE < pos[i] < high[i] + CUBE_HALF_SIZE for i in (0, 1)):
                raise EnvOptionError(f"{where} cuts into {obstacle}")


def _resting_surface(pos: np.ndarray) -> str | None:
    """The surface of ``CUBE_RESTS`` a cube at ``pos`` rests on, if any."""
    h = CUBE_HALF_SIZE
    for surface, (low, high) in CUBE_RESTS.items():
        over = low[0] + h <= pos[0] <= high[0] - h and low[1] + h <= pos[1] <= high[1] - h
        if over and low[2] + h <= pos[2] <= low[2] + h + REST_TOLERANCE:
            return surface
    return None
