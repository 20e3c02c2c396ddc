"""Validation of the kitchen's ``world`` reset options (door travel, cube position)."""

from __future__ import annotations

from typing import Any

from osg_control.environment.options import finite_option
from osg_control.errors import EnvOptionError

DOOR_TRAVEL = 0.45
"""The door slide's range [m] (``robots/kitchen.xml``)."""


def check_world_options(world: dict[str, Any]) -> None:
    """Refuse a non-finite or out-of-range door opening or cube position.

    Raises:
        EnvOptionError: naming the option and its value.
    """
    door = float(finite_option("world.door_opening", world.get("door_opening", 0.0)))
    if not 0.0 <= door <= DOOR_TRAVEL:
        raise EnvOptionError(
            f"reset option world.door_opening must lie in [0, {DOOR_TRAVEL}] m, got {door}"
        )
    if world.get("cube_pos") is not None:
        finite_option("world.cube_pos", world["cube_pos"], (3,))
