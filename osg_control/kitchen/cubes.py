"""The kitchen's cubes beyond the first: where they rest, their colours and object frames,
their sensors, and how many a scene may hold (numpy only, no MuJoCo).

Cube 1 is ``robots/kitchen.xml``'s; cubes 2 and 3 are copies of it added when the model is
composed (``scene.kitchen_spec``), each its own colour, so the one-cube model is the file's
exactly. Each cube has its frame (``cube``, ``cube2`` ...): the cube's nodes are given for
cube 1's nominal place, so every frame shares that nominal and a skill bound to cube k acts
in cube k's displacement from it (``domain.binding``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from osg_control.domain.spec import ObjectFrame
from osg_control.errors import EnvOptionError
from osg_control.kitchen.objects import MAX_CUBES, cube_fact, cube_prefix
from osg_control.kitchen.skills import CUBE, OBJECTS
from osg_control.kitchen.world import CUBE_FIELDS
from osg_control.perception.sensors import DETECTED, POSITION, QUATERNION

CUBE_CLEARANCE = 0.045
"""Half the least distance [m] between two cubes' centres where they are placed: 9 cm,
the cube's 4.5 cm edge plus room for an open finger (a grasp closes along y) beside it."""
REST_PLACES: tuple[tuple[float, float], ...] = ((0.50, -0.20), (0.41, -0.11), (0.59, -0.11))
"""Where each cube rests in the scene as composed (x, y) [m]: cube 1 at its nominal
place, the others in the corners of its square toward the cabinet, 12.7 cm from it."""
COLOURS: tuple[tuple[float, float, float, float], ...] = (
    (0.85, 0.15, 0.15, 1.0),
    (0.15, 0.35, 0.85, 1.0),
    (0.90, 0.80, 0.10, 1.0),
)
"""Each cube's colour: red (the file's), blue, yellow."""
CUBE_SENSORS: dict[str, str] = {
    "x": POSITION, "y": POSITION, "z": POSITION,
    "qw": QUATERNION, "qx": QUATERNION, "qy": QUATERNION, "qz": QUATERNION,
    "grasped": DETECTED,
}  # fmt: skip
"""The sensor of each of a cube's world fields (``CUBE_FIELDS``)."""
assert tuple(CUBE_SENSORS) == CUBE_FIELDS


def check_cubes(cubes: Any) -> int:
    """``cubes`` as a cube count of a kitchen scene.

    Raises:
        EnvOptionError: not a whole number from 1 to ``MAX_CUBES``, naming it.
    """
    if isinstance(cubes, bool) or not isinstance(cubes, int) or not 1 <= cubes <= MAX_CUBES:
        raise EnvOptionError(
            f"the kitchen holds 1 to {MAX_CUBES} cubes (its counter square fits no more with "
            f"{2 * CUBE_CLEARANCE:.2f} m between them), got cubes={cubes!r}"
        )
    return cubes


def cube_frame(k: int) -> ObjectFrame:
    """Cube k's object frame among several (``skills.CUBE`` with ``CUBE_CLEARANCE``, its
    own fields and held fact)."""
    prefix = cube_prefix(k)
    return replace(
        CUBE,
        name=prefix,
        position_fields=(f"{prefix}_x", f"{prefix}_y"),
        held_fact=cube_fact("holding-cube", k),
        clearance=CUBE_CLEARANCE,
    )


def cube_objects(cubes: int) -> tuple[ObjectFrame, ...]:
    """The objects nodes may be anchored to with ``cubes`` cubes: ``skills.OBJECTS`` (one
    cube), or each cube's frame (placed clear of each other) and the door's."""
    if cubes == 1:
        return OBJECTS
    return tuple(cube_frame(k) for k in range(1, cubes + 1)) + OBJECTS[1:]


def cube_sensors(cubes: int) -> dict[str, str]:
    """The world fields' sensors of cubes 2 ... ``cubes`` (after the one-cube vector's)."""
    return {
        f"{cube_prefix(k)}_{name}": kind
        for k in range(2, cubes + 1)
        for name, kind in CUBE_SENSORS.items()
    }
