"""IK edge cases: the joint-reset QP at (and a little past) the joint limits falls back to
holding the pose instead of raising; rotation targets that are not rotations are refused."""

from __future__ import annotations

import numpy as np
import pytest

from osg_control.control.ik import DiffIKController, joint_reset_controller
from osg_control.errors import ControllerError
from osg_control.robots.panda import PANDA

HOME_Q = PANDA.home_q


@pytest.fixture(scope="module")
def reset_ik() -> DiffIKController:
    return joint_reset_controller(PANDA)


def _at_limits(ik: DiffIKController) -> list[np.ndarray]:
    configurations = []
    for joint in range(7):
        for value in (
            ik.backend.lower[joint],
            ik.backend.upper[joint],
            ik.backend.lower[joint] - 1e-3,
            ik.backend.upper[joint] + 1e-3,
        ):
            q = np.array(HOME_Q, dtype=float)
            q[joint] = value
            configurations.append(q)
    return configurations


def test_joint_reset_at_the_limits_never_raises_and_keeps_the_tcp(reset_ik) -> None:
    for q in _at_limits(reset_ik):
        pos, rot = reset_ik.tcp_pose(q)
        q_next = reset_ik.reset_step(q, pos, rot)
        assert q_next.shape == (7,) and np.all(np.isfinite(q_next))
        moved_pos, _ = reset_ik.tcp_pose(
            np.clip(q_next, reset_ik.backend.lower, reset_ik.backend.upper)
        )
        held = np.allclose(q_next, q)
        assert held or np.linalg.norm(moved_pos - pos) < 0.01, q


def test_relative_step_a_little_past_a_limit_is_solved() -> None:
    ik = DiffIKController(PANDA)
    q = np.array(HOME_Q, dtype=float)
    q[3] = ik.backend.upper[3] + 1e-3
    q_next = ik.relative_step(q, np.array([0.01, 0.0, 0.0, 0.0, 0.0, 0.0]))
    assert np.all(q_next <= ik.backend.upper) and np.all(q_next >= ik.backend.lower)


@pytest.mark.parametrize(
    "rot",
    [
        np.eye(3) * 1.01,  # scaled
        np.diag([1.0, 1.0, -1.0]),  # a reflection (det -1)
        np.array([[1.0, 0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),  # shear
        np.zeros((3, 3)),
    ],
)
def test_non_rotation_targets_are_refused(rot: np.ndarray) -> None:
    ik = DiffIKController(PANDA)
    pos, _ = ik.tcp_pose(np.array(HOME_Q))
    with pytest.raises(ControllerError, match="orthonormal"):
        ik.solve_velocity(np.array(HOME_Q), pos, rot)


def test_a_proper_rotation_is_accepted() -> None:
    ik = DiffIKController(PANDA)
    pos, rot = ik.tcp_pose(np.array(HOME_Q))
    assert np.all(np.isfinite(ik.solve_velocity(np.array(HOME_Q), pos, rot)))
