"""The 7-D relative TCP action: validation before anything reaches the actuators, and
scaling that keeps a command's direction."""

from __future__ import annotations

from typing import Any

import numpy as np

from osg_control.environment.success import GRIPPER_CLOSED_CMD, GRIPPER_OPEN_CMD

REAL_KINDS = "iuf"
"""numpy dtype kinds an action may have: signed and unsigned integers, floats (not bool,
complex, strings or objects)."""


def checked_action(action: Any, bounds: np.ndarray) -> np.ndarray:
    """Validate an action (real numbers, shape (7,), finite) and clip it to ``bounds``.

    Raises:
        ValueError: not real numbers, wrong shape or NaN/inf (the message names the
            expected shape and bounds); nothing reaches the actuators.
    """
    try:
        array = np.asarray(action)
    except ValueError:  # a ragged sequence
        raise ValueError(_refusal(bounds, repr(action))) from None
    if array.dtype.kind not in REAL_KINDS:
        raise ValueError(_refusal(bounds, f"dtype {array.dtype}: {action!r}"))
    if array.shape != (7,):
        raise ValueError(_refusal(bounds, f"shape {array.shape}"))
    if not np.isfinite(array).all():
        raise ValueError(_refusal(bounds, f"non-finite values {array.tolist()}"))
    return np.minimum(np.maximum(array, -bounds), bounds)  # float64 for every real kind


def _refusal(bounds: np.ndarray, got: str) -> str:
    """The message of a refused action."""
    return f"action must be a finite real array of shape (7,) within +-{bounds.tolist()}, got {got}"


def latched_gripper(command: float, g: float) -> float:
    """The gripper command after an action whose gripper component is ``g``: ``g < -0.5``
    closes, ``g > 0.5`` opens, anything between leaves ``command`` as it was (a latch)."""
    if g < -0.5:
        return GRIPPER_CLOSED_CMD
    if g > 0.5:
        return GRIPPER_OPEN_CMD
    return command


def scale_into(vector: np.ndarray, bound: float) -> np.ndarray:
    """Scale a vector so that no component exceeds ``bound``, keeping its direction."""
    largest = float(np.abs(vector).max())
    return vector * (bound / largest) if largest > bound else vector
