"""Validation of ``ArmEnv.reset`` options: a start that means nothing is refused.

A NaN start position or scene option would otherwise make MuJoCo reset to its default pose
and the episode run from a world nobody asked for.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from osg_control.errors import EnvOptionError


def finite_option(name: str, value: Any, shape: tuple[int, ...] = ()) -> np.ndarray:
    """``value`` as a finite float array of ``shape``, else ``EnvOptionError`` naming it."""
    array = np.asarray(value, dtype=float)
    if array.shape != shape or not np.all(np.isfinite(array)):
        raise EnvOptionError(f"reset option {name} must be finite of shape {shape}, got {value!r}")
    return array


def check_start_options(centre: np.ndarray, radius: float, angle: float) -> None:
    """Refuse a non-finite or negative start pose option.

    Raises:
        EnvOptionError: naming the option and its value.
    """
    finite_option("position", centre, (3,))
    for name, value in (("radius", radius), ("angle", angle)):
        if finite_option(name, value) < 0:
            raise EnvOptionError(f"reset option {name} must be >= 0, got {value!r}")
