"""Validation of ``KitchenEnv.reset`` options: a start that means nothing is refused.

A NaN door opening would otherwise make MuJoCo reset to its default pose and the episode
run from a world nobody asked for.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from osg_control.errors import EnvOptionError

DOOR_TRAVEL = 0.45
"""The door slide's range [m] (``robots/kitchen.xml``)."""


def _finite(name: str, value: Any, shape: tuple[int, ...] = ()) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.shape != shape or not np.all(np.isfinite(array)):
        raise EnvOptionError(f"reset option {name} must be finite of shape {shape}, got {value!r}")
    return array


def check_start_options(
    centre: np.ndarray, radius: float, angle: float, world: dict[str, Any]
) -> None:
    """Refuse non-finite or out-of-range start options.

    Raises:
        EnvOptionError: naming the option and its value.
    """
    _finite("position", centre, (3,))
    for name, value in (("radius", radius), ("angle", angle)):
        if _finite(name, value) < 0:
            raise EnvOptionError(f"reset option {name} must be >= 0, got {value!r}")
    door = float(_finite("world.door_opening", world.get("door_opening", 0.0)))
    if not 0.0 <= door <= DOOR_TRAVEL:
        raise EnvOptionError(
            f"reset option world.door_opening must lie in [0, {DOOR_TRAVEL}] m, got {door}"
        )
    if world.get("cube_pos") is not None:
        _finite("world.cube_pos", world["cube_pos"], (3,))
