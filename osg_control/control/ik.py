r"""Differential IK for any arm: one QP per control step, two interchangeable backends.

At each step we solve for the joint displacement :math:`\Delta q = v\,dt` [rad]

.. math::

    \min_{\Delta q} \; \tfrac12 \|W_{tcp} (J_{tcp} \Delta q + g\,e_{tcp})\|^2
            + \tfrac12 w_{post}^2 \|\Delta q + g\,(q - q_{post})\|^2
            + \tfrac12 (\lambda + \mu) \|\Delta q\|^2
    \quad \text{s.t.} \quad
    \max(\gamma (q_{min} - q), -v_{max} dt) \le \Delta q \le
    \min(\gamma (q_{max} - q), v_{max} dt)

with a TCP frame task (error :math:`e_{tcp} = \log(T_{bt})`, a body twist in the TCP
frame, and Jacobian :math:`J_{tcp} = -\mathrm{Jlog}_6(T_{tb})\,{}_bJ_{0b}(q)`), a
low-weight posture task, Tikhonov damping :math:`\lambda`, Levenberg-Marquardt damping
:math:`\mu = \epsilon_{lm} \|g W_{tcp} e_{tcp}\|^2`, and joint position and velocity limits
always enforced. This is exactly the QP that ``mink.build_ik`` and ``pink.build_ik`` build
from a ``FrameTask``, a ``PostureTask``, a ``ConfigurationLimit`` (gain :math:`\gamma`) and
a ``VelocityLimit``; the two limits are merged into one box because both are bounds on
:math:`\Delta q`. In a joint reset (``hard_tcp``) the TCP task becomes the equality
:math:`J_{tcp} \Delta q = -g\,e_{tcp}` and leaves the objective.

The QP is composed, as ``build_ik`` does, from open lists (``control.ik_tasks``): tasks,
each adding its Hessian and linear terms (the frame and posture tasks above, then any the
caller passes, e.g. ``DampingTask`` or another ``PostureTask``), and limits, each bounding
:math:`\Delta q` (the two above, then any the caller passes), intersected into one box.
Backends compute :math:`e_{tcp}` and :math:`J_{tcp}`; the QP around them is composed by
shared code, so both backends build the same QP by construction:

- ``mink``: mink's ``FrameTask`` on the robot's arm-only MuJoCo model (default);
- ``pinocchio``: Pink's frame-task formulas evaluated directly with Pinocchio on the
  robot's arm-only Pinocchio model (no simulator)

(``control.ik_backends``; the arm is a ``RobotDescription``, of any number of joints).

Solvers: ``daqp`` (default; dense active set, called directly with the box as simple
bounds) and ``osqp`` (ADMM on sparse CSC matrices, absolute and relative tolerance
``IKConfig.osqp_eps``). The QP is strongly convex but ill-conditioned: along a 7-joint
arm's 1-D null space its curvature is only ``posture_cost**2 + damping`` (about 1e-6 by default), so
OSQP's residual tolerance pins the null-space part of its answer only loosely. With the
default ``osqp_eps = 1e-9``, OSQP's TCP velocity ``J v`` matches DAQP's exact active-set
solution to about 1e-6 and joint-reset velocities (posture cost 1) to about 1e-7 rad/s,
while the null-space part of ``v`` can differ by a few 1e-2 rad/s.

A joint reset moves the joints in the null space of the TCP task, which only an arm of more
than six joints has (``DiffIKController.has_null_space``); on another arm it holds ``q``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.control.ik_backends import BACKENDS, Backend, IKConfig
from osg_control.control.ik_tasks import Limit, Task
from osg_control.control.qp import qp_solver
from osg_control.control.rotations import check_rotation, rotation_error, rotation_step
from osg_control.errors import ControllerError

__all__ = [
    "BACKENDS",
    "DiffIKController",
    "IKConfig",
    "InfeasibleQPError",
    "joint_reset_controller",
    "solve_ik",
]


class InfeasibleQPError(ControllerError):
    """The IK QP has no solution for this configuration and target."""


class DiffIKController:
    """Turns TCP targets or relative TCP commands into joint position targets.

    Args:
        robot: the arm.
        config: weights, gains, backend and solver (default ``IKConfig()``).
        tasks: costs added to the TCP frame and posture tasks (``control.ik_tasks``, e.g.
            ``DampingTask(0.1)``).
        limits: bounds on ``dq`` added to the joint position and velocity limits.

    Example:
        >>> ik = DiffIKController(robot, IKConfig(backend="mink"))  # robot: a description
        >>> q_next = ik.relative_step(ik.posture, np.array([0.01, 0, 0, 0, 0, 0]))
    """

    def __init__(
        self,
        robot: RobotDescription,
        config: IKConfig | None = None,
        tasks: Sequence[Task] = (),
        limits: Sequence[Limit] = (),
    ) -> None:
        self.config = config or IKConfig()
        self.robot = robot
        self.backend: Backend = BACKENDS[self.config.backend](self.config, robot, tasks, limits)
        self._solve_qp = qp_solver(self.config.solver, self.config.osqp_eps, robot.n_joints)
        self._n = robot.n_joints

    @property
    def posture(self) -> np.ndarray:
        """The posture task's target [rad] (the robot's home unless configured)."""
        return self.backend.posture

    @property
    def has_null_space(self) -> bool:
        """Whether the arm can move with its TCP pose held (more than six joints): only
        then does ``reset_step`` move the joints."""
        return self.robot.redundant

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics: TCP position [m] and rotation matrix in the base frame."""
        return self.backend.tcp_pose(self._check_q(q))

    def _check_q(self, q: np.ndarray) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape != (self._n,) or not np.isfinite(q).all():
            raise ControllerError(f"joint configuration must be {self._n} finite values, got {q!r}")
        return q

    def solve_velocity(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray, hard_tcp: bool = False
    ) -> np.ndarray:
        """Solve the QP for joint velocities [rad/s] toward a TCP target.

        Args:
            q: current arm configuration [rad] (n,).
            target_pos: TCP target position [m] (3,), base frame.
            target_rot: TCP target rotation matrix (3, 3).
            hard_tcp: keep the TCP task as an equality constraint (joint reset).

        Raises:
            ControllerError: non-finite input or the solver found no solution.
        """
        q = self._check_q(q)
        target_pos = np.asarray(target_pos, dtype=float)
        target_rot = np.asarray(target_rot, dtype=float)
        if (
            target_pos.shape != (3,)
            or target_rot.shape != (3, 3)
            or not (np.isfinite(target_pos).all() and np.isfinite(target_rot).all())
        ):
            raise ControllerError("TCP target must be a finite position (3,) and rotation (3, 3)")
        check_rotation(target_rot)
        return self._solve(q, target_pos, target_rot, hard_tcp)

    def _solve(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray, hard_tcp: bool
    ) -> np.ndarray:
        """``solve_velocity`` on inputs already checked. A ``q`` a little past a joint limit
        (contacts can push it there) is linearised at the limit, where the QP is feasible."""
        q = np.minimum(np.maximum(q, self.backend.lower), self.backend.upper)
        problem = self.backend.build_qp(q, target_pos, target_rot, hard_tcp)
        solution = self._solve_qp(problem)
        if solution is None:
            raise InfeasibleQPError(
                f"QP solver {self.config.solver!r} found no solution at q={q.round(4)}"
            )
        return solution / self.config.dt  # the QP's unknown is dq = v dt

    def step(self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray) -> np.ndarray:
        """One IK step: the next joint target ``q + v dt`` [rad], clipped to the joint limits."""
        velocity = self.solve_velocity(q, target_pos, target_rot)
        return self._integrate(np.asarray(q, dtype=float), velocity)

    def _integrate(self, q: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        next_q = np.maximum(q + velocity * self.config.dt, self.backend.lower)
        return np.minimum(next_q, self.backend.upper)

    def relative_step(self, q: np.ndarray, delta: np.ndarray) -> np.ndarray:
        """Apply a relative TCP command ``[dx, dy, dz, da, db, dg]`` ([m], [rad], base frame).

        Returns:
            The next joint position target [rad].
        """
        delta = np.asarray(delta, dtype=float)
        if delta.shape != (6,) or not np.isfinite(delta).all():
            raise ControllerError(f"relative TCP command must be 6 finite values, got {delta!r}")
        q = self._check_q(q)
        pos, rot = self.backend.tcp_pose(q)
        velocity = self._solve(q, pos + delta[:3], rotation_step(rot, delta[3:]), False)
        return self._integrate(q, velocity)

    def reset_step(self, q: np.ndarray, tcp_pos: np.ndarray, tcp_rot: np.ndarray) -> np.ndarray:
        """One joint-reset step: move toward the posture while holding the TCP pose fixed.

        Where no such step exists (an arm without a null space, ``has_null_space``; or the
        QP is infeasible, e.g. joints pinned at their limits with the TCP pose held), the
        fallback is to hold ``q``: the reset ends there and the TCP keeps its pose, instead
        of a ``ControllerError``.
        """
        if not self.has_null_space:
            return self._check_q(q).copy()
        try:
            velocity = self.solve_velocity(q, tcp_pos, tcp_rot, hard_tcp=True)
        except InfeasibleQPError:
            return self._check_q(q).copy()
        return self._integrate(np.asarray(q, dtype=float), velocity)


def joint_reset_controller(
    robot: RobotDescription, config: IKConfig | None = None
) -> DiffIKController:
    """A controller tuned for joint reset: the posture task dominates in the null space."""
    base = config or IKConfig()
    return DiffIKController(robot, replace(base, posture_cost=1.0, gain=0.5))


def solve_ik(
    controller: DiffIKController,
    q0: np.ndarray,
    target_pos: np.ndarray,
    target_rot: np.ndarray,
    *,
    iterations: int = 200,
    pos_tol: float = 1e-4,
    rot_tol: float = 1e-3,
) -> tuple[np.ndarray, bool]:
    """Iterate the differential IK to convergence (used to place the arm at a TCP pose).

    Returns:
        The final configuration [rad] and whether it is within ``pos_tol`` [m] and
        ``rot_tol`` [rad] of the target.
    """
    q = np.asarray(q0, dtype=float).copy()
    for _ in range(iterations):
        pos, rot = controller.tcp_pose(q)
        if (
            np.linalg.norm(pos - target_pos) < pos_tol
            and np.linalg.norm(rotation_error(rot, target_rot)) < rot_tol
        ):
            return q, True
        q = controller.step(q, target_pos, target_rot)
    pos, rot = controller.tcp_pose(q)
    converged = bool(
        np.linalg.norm(pos - target_pos) < pos_tol
        and np.linalg.norm(rotation_error(rot, target_rot)) < rot_tol
    )
    return q, converged
