"""Joint position targets spread over a control step's physics substeps.

The IK bounds each control step's joint motion by the URDF velocity limits, but a position
servo handed the whole step at once chases it with a velocity peak well above them (up to
2.7x). Here the servo's target moves along the straight line from the previous target to
the new one as fast as the limits allow (``max_increment`` per substep for every joint),
then holds: a small step is reached early in the control step, as before, and no joint is
commanded faster than its limit.
"""

from __future__ import annotations

import math

import numpy as np


def substep_targets(
    previous: np.ndarray, target: np.ndarray, substeps: int, max_increment: np.ndarray
) -> np.ndarray:
    """(substeps, n) targets from ``previous`` to ``target``: a ramp of the fewest substeps
    whose per-substep increments stay within ``max_increment`` (n,), then ``target``."""
    delta = np.asarray(target, dtype=float) - previous
    ratio = float(np.max(np.abs(delta) / max_increment, initial=0.0))
    ramp = min(substeps, max(1, math.ceil(ratio - 1e-9)))
    fractions = np.minimum(np.arange(1, substeps + 1, dtype=float) / ramp, 1.0)[:, None]
    return previous + fractions * delta
