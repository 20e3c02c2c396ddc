"""Rotation helpers of the IK and the scripts: MuJoCo's quaternion routines on 3x3
matrices and rotation vectors (world frame)."""

from __future__ import annotations

import mujoco
import numpy as np

from osg_control.errors import ControllerError


def rotation_step(rot: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """Rotate ``rot`` by the world-frame rotation vector ``delta`` [rad]."""
    quat = np.array([1.0, 0.0, 0.0, 0.0])
    mujoco.mju_quatIntegrate(quat, np.asarray(delta, dtype=float), 1.0)
    return quat_to_matrix(quat) @ rot


def rotation_error(current: np.ndarray, target: np.ndarray) -> np.ndarray:
    """World-frame rotation vector [rad] taking ``current`` to ``target``."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, (target @ current.T).ravel())
    rotvec = np.zeros(3)
    mujoco.mju_quat2Vel(rotvec, quat, 1.0)
    return rotvec


ORTHONORMAL_TOL = 1e-6


def check_rotation(rot: np.ndarray) -> None:
    """Refuse a rotation target that is not a rotation matrix.

    Raises:
        ControllerError: ``rot`` is not orthonormal (within ``ORTHONORMAL_TOL``) with det +1.
    """
    error = float(np.abs(rot.T @ rot - np.eye(3)).max())
    if error > ORTHONORMAL_TOL or np.linalg.det(rot) < 0:
        raise ControllerError(
            f"TCP rotation target must be orthonormal with determinant +1 (|R^T R - I| = "
            f"{error:.2g}, det {np.linalg.det(rot):.3g})"
        )


def quat_to_matrix(quat_wxyz: np.ndarray) -> np.ndarray:
    """Rotation matrix of a ``w, x, y, z`` quaternion (MuJoCo's order)."""
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat_wxyz, dtype=float))
    return mat.reshape(3, 3)
