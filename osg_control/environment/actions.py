"""The 7-D relative TCP action: validation before anything reaches the actuators, and
scaling that keeps a command's direction."""

from __future__ import annotations

import numpy as np


def checked_action(action: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """Validate an action (shape (7,), finite) and clip it to ``bounds``.

    Raises:
        ValueError: wrong shape or NaN/inf; nothing reaches the actuators.
    """
    action = np.asarray(action, dtype=float)
    if action.shape != (7,):
        raise ValueError(f"action must have shape (7,), got {action.shape}")
    if not np.all(np.isfinite(action)):
        raise ValueError(f"action must be finite, got {action.tolist()}")
    return np.clip(action, -bounds, bounds)


def scale_into(vector: np.ndarray, bound: float) -> np.ndarray:
    """Scale a vector so that no component exceeds ``bound``, keeping its direction."""
    largest = float(np.abs(vector).max())
    return vector * (bound / largest) if largest > bound else vector
