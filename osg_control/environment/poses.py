"""TCP poses of the env: random starts around a node."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.domain.spec import TOP_DOWN_QUAT

_TOP_DOWN_ROT = Rotation.from_quat(np.roll(np.array(TOP_DOWN_QUAT), -1))


def quat_rotation(quat_wxyz: tuple[float, float, float, float]) -> Rotation:
    """A ``w, x, y, z`` quaternion as a SciPy rotation."""
    return Rotation.from_quat(np.roll(np.asarray(quat_wxyz, dtype=float), -1))


def sample_start_pose(
    rng: np.random.Generator,
    centre: np.ndarray,
    radius: float,
    angle: float,
    orientation: Rotation = _TOP_DOWN_ROT,
) -> tuple[np.ndarray, np.ndarray]:
    """A TCP pose uniform in a ball of ``radius`` [m] around ``centre`` and within ``angle``
    [rad] per axis of ``orientation`` (default top-down). Returns (position, rotation
    matrix)."""
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction) + 1e-12
    position = centre + direction * radius * rng.uniform() ** (1 / 3)
    euler = rng.uniform(-angle, angle, size=3)
    rot = Rotation.from_euler("xyz", euler) * orientation
    return position, rot.as_matrix()
