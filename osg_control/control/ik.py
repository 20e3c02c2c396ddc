r"""Differential IK for the Panda: one QP per control step, two interchangeable backends.

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

Backends compute :math:`e_{tcp}` and :math:`J_{tcp}`; the QP around them is assembled by
shared code, so both backends build the same QP by construction:

- ``mink``: mink's ``FrameTask`` on the arm-only MuJoCo model compiled from the URDF
  (default);
- ``pinocchio``: Pink's frame-task formulas evaluated directly with Pinocchio on the model
  loaded from the same URDF (no simulator).

Solvers: ``daqp`` (default; dense active set, called directly with the box as simple
bounds) and ``osqp`` (ADMM on sparse CSC matrices, absolute and relative tolerance
``IKConfig.osqp_eps``). The QP is strongly convex but ill-conditioned: along the arm's 1-D
null space its curvature is only ``posture_cost**2 + damping`` (about 1e-6 by default), so
OSQP's residual tolerance pins the null-space part of its answer only loosely. With the
default ``osqp_eps = 1e-9``, OSQP's TCP velocity ``J v`` matches DAQP's exact active-set
solution to about 1e-6 and joint-reset velocities (posture cost 1) to about 1e-7 rad/s,
while the null-space part of ``v`` can differ by a few 1e-2 rad/s.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import mujoco
import numpy as np
import qpsolvers

from osg_control.control.qp import SOLVERS, qp_solver
from osg_control.control.robot import (
    HOME_Q,
    TCP_FRAME,
    TCP_SITE,
    load_pinocchio_arm,
    panda_spec,
    urdf_velocity_limits,
)
from osg_control.control.rotations import check_rotation, rotation_error, rotation_step
from osg_control.errors import ControllerError


@dataclass(frozen=True)
class IKConfig:
    """Weights, gains and limits of the differential-IK QP.

    Attributes:
        backend: ``"mink"`` (MuJoCo model) or ``"pinocchio"`` (Pinocchio on the URDF).
        solver: the QP solver: ``"daqp"`` (default) or ``"osqp"``.
        dt: integration step of one solve [s] (the env's control period).
        position_cost: TCP position task weight [1/m].
        orientation_cost: TCP orientation task weight [1/rad].
        posture_cost: posture task weight toward ``posture`` [1/rad] (keep it low).
        gain: task gain in (0, 1]: the fraction of the error to remove in one step.
        lm_damping: Levenberg-Marquardt damping of the frame task (unitless).
        damping: Tikhonov regularisation of the QP (unitless).
        limit_gain: configuration-limit gain in (0, 1] (how fast limits may be approached).
        velocity_scale: fraction of the URDF's joint velocity limits allowed.
        posture: nominal arm configuration [rad]; the home pose by default.
        osqp_eps: OSQP's absolute and relative tolerance (only with ``solver="osqp"``).
    """

    backend: str = "mink"
    solver: str = "daqp"
    dt: float = 0.05
    position_cost: float = 1.0
    orientation_cost: float = 0.5
    posture_cost: float = 1e-3
    gain: float = 1.0
    lm_damping: float = 1e-6
    damping: float = 1e-9
    limit_gain: float = 0.95
    velocity_scale: float = 1.0
    posture: tuple[float, ...] = tuple(HOME_Q)
    osqp_eps: float = 1e-9

    def __post_init__(self) -> None:
        if self.backend not in BACKENDS:
            raise ControllerError(f"unknown IK backend {self.backend!r}; known: {sorted(BACKENDS)}")
        if self.solver not in SOLVERS:
            raise ControllerError(f"unknown QP solver {self.solver!r}; supported: {SOLVERS}")
        if self.solver not in qpsolvers.available_solvers:
            raise ControllerError(
                f"QP solver {self.solver!r} is not installed; available: "
                f"{qpsolvers.available_solvers}"
            )
        if not (0.0 < self.gain <= 1.0 and 0.0 < self.limit_gain <= 1.0 and self.dt > 0):
            raise ControllerError("IKConfig: gain and limit_gain must be in (0, 1], dt > 0")
        if len(self.posture) != 7:
            raise ControllerError(f"IKConfig: posture has {len(self.posture)} values, expected 7")


class Backend:
    """Kinematics of the TCP frame task plus the QP assembly shared by every backend.

    Subclasses implement ``tcp_pose`` and ``frame_residual``; ``build_qp`` is common, so
    all backends build the same QP.

    Attributes:
        config: the controller's configuration.
        lower: joint lower limits [rad] (7,).
        upper: joint upper limits [rad] (7,).
        velocity_limit: joint velocity limits [rad/s] (7,), the URDF's times
            ``velocity_scale``.
    """

    def __init__(self, config: IKConfig, lower: np.ndarray, upper: np.ndarray) -> None:
        self.config = config
        self.lower = np.array(lower, dtype=float)
        self.upper = np.array(upper, dtype=float)
        self.velocity_limit = urdf_velocity_limits() * config.velocity_scale
        # Constants of the QP, so that build_qp does the per-step arithmetic only.
        cost = np.array([config.position_cost] * 3 + [config.orientation_cost] * 3)
        self._cost_column = cost[:, None]
        self._gain_cost = config.gain * cost
        self._posture = np.asarray(config.posture, dtype=float)
        self._posture_gain = config.posture_cost**2 * config.gain
        self._diagonal = config.posture_cost**2 + config.damping
        # Both box rows at once: lower = max(gain (lower - q), -step), upper = min(gain
        # (upper - q), step), as one clip of a (2, 7) array between these rows.
        step_limit = self.velocity_limit * config.dt
        self._limits = np.stack([self.lower, self.upper])
        self._box_floor = np.stack([-step_limit, np.full(7, -np.inf)])
        self._box_ceiling = np.stack([np.full(7, np.inf), step_limit])

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """TCP position [m] and rotation matrix in the base frame at ``q``."""
        raise NotImplementedError

    def frame_residual(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """TCP task error ``log(T_bt)`` (6,) and its Jacobian (6, 7) at ``q``.

        The error is a body twist in the TCP frame, linear part first.
        """
        raise NotImplementedError

    def build_qp(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray, hard_tcp: bool
    ) -> qpsolvers.Problem:
        """Assemble the QP in ``dq = v dt`` at ``q`` toward the target.

        Args:
            q: arm configuration [rad] (7,).
            target_pos: TCP target position [m] (3,).
            target_rot: TCP target rotation matrix (3, 3).
            hard_tcp: make the TCP task an equality constraint (joint reset).

        Returns:
            ``qpsolvers.Problem`` with ``P``, ``q``, box bounds ``lb``/``ub`` and, if
            ``hard_tcp``, the equality ``A dq = b``; no general inequalities.
        """
        config = self.config
        error, jacobian = self.frame_residual(q, target_pos, target_rot)
        linear = self._posture_gain * (q - self._posture)
        if hard_tcp:
            hessian = np.zeros((7, 7))
            hessian.flat[::8] = self._diagonal
            equality_matrix: np.ndarray | None = jacobian
            equality_vector: np.ndarray | None = -config.gain * error
        else:
            weighted_error = self._gain_cost * error
            weighted_jacobian = self._cost_column * jacobian
            hessian = weighted_jacobian.T @ weighted_jacobian
            linear += weighted_error @ weighted_jacobian
            lm_term = config.lm_damping * float(weighted_error @ weighted_error)
            hessian.flat[::8] += self._diagonal + lm_term
            equality_matrix = equality_vector = None
        box = np.minimum(
            np.maximum(config.limit_gain * (self._limits - q), self._box_floor), self._box_ceiling
        )
        return qpsolvers.Problem(
            hessian, linear, A=equality_matrix, b=equality_vector, lb=box[0], ub=box[1]
        )


class MinkBackend(Backend):
    """mink's ``FrameTask`` on the arm-only MuJoCo model compiled from the URDF."""

    def __init__(self, config: IKConfig) -> None:
        import mink

        self.model = panda_spec(with_fingers=False).compile()
        super().__init__(config, self.model.jnt_range[:, 0], self.model.jnt_range[:, 1])
        self.configuration = mink.Configuration(self.model)
        self.frame_task = mink.FrameTask(
            TCP_SITE,
            "site",
            position_cost=config.position_cost,
            orientation_cost=config.orientation_cost,
            gain=config.gain,
            lm_damping=config.lm_damping,
        )
        # The task's target is this SE3, overwritten in place each step (``set_target``
        # would build and copy a new one every time).
        self._target = mink.SE3(np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
        self.frame_task.transform_target_to_world = self._target
        self._site = self.model.site(TCP_SITE).id
        self._posed_at = np.full(7, np.nan)  # the configuration's q (NaN: none yet)

    def _pose(self, q: np.ndarray) -> None:
        """Forward kinematics at ``q``, unless the configuration is there already (a
        relative step or an IK iteration reads the pose, then linearises at the same q)."""
        if not (q == self._posed_at).all():
            self.configuration.update(q)
            self._posed_at[:] = q

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self._pose(q)
        data = self.configuration.data
        return data.site_xpos[self._site].copy(), data.site_xmat[self._site].reshape(3, 3).copy()

    def frame_residual(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        self._pose(q)
        target = self._target.wxyz_xyz
        mujoco.mju_mat2Quat(target[:4], target_rot.ravel())
        target[4:] = target_pos
        return (
            self.frame_task.compute_error(self.configuration),
            self.frame_task.compute_jacobian(self.configuration),
        )


class PinocchioBackend(Backend):
    """Pink's frame-task formulas, evaluated with Pinocchio on the URDF (no MuJoCo).

    ``e = log6(T_bt)`` and ``J = -Jlog6(T_tb) J_b`` as in ``pink.tasks.FrameTask``, computed
    without Pink's per-call ``Configuration`` and ``SE3`` copies.
    """

    def __init__(self, config: IKConfig) -> None:
        import pinocchio as pin

        self.model = load_pinocchio_arm()
        super().__init__(config, self.model.lowerPositionLimit, self.model.upperPositionLimit)
        self.model.velocityLimit = self.velocity_limit.copy()
        self.data = self.model.createData()
        self.frame_id = self.model.getFrameId(TCP_FRAME)
        self._pin = pin

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self._pin.framesForwardKinematics(self.model, self.data, q)
        placement = self.data.oMf[self.frame_id]
        return placement.translation.copy(), placement.rotation.copy()

    def frame_residual(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        pin = self._pin
        pin.computeJointJacobians(self.model, self.data, q)
        frame = pin.updateFramePlacement(self.model, self.data, self.frame_id)
        target = pin.SE3(target_rot, target_pos)
        error = pin.log6(frame.actInv(target)).vector
        jacobian = pin.getFrameJacobian(self.model, self.data, self.frame_id, pin.LOCAL)
        return error, -pin.Jlog6(target.actInv(frame)) @ jacobian


BACKENDS: dict[str, Callable[[IKConfig], Backend]] = {
    "mink": MinkBackend,
    "pinocchio": PinocchioBackend,
}


class InfeasibleQPError(ControllerError):
    """The IK QP has no solution for this configuration and target."""


class DiffIKController:
    """Turns TCP targets or relative TCP commands into joint position targets.

    Example:
        >>> ik = DiffIKController(IKConfig(backend="mink", solver="daqp"))
        >>> q_next = ik.relative_step(HOME_Q, np.array([0.01, 0, 0, 0, 0, 0]))
    """

    def __init__(self, config: IKConfig | None = None) -> None:
        self.config = config or IKConfig()
        self.backend: Backend = BACKENDS[self.config.backend](self.config)
        self._solve_qp = qp_solver(self.config.solver, self.config.osqp_eps)

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics: TCP position [m] and rotation matrix in the base frame."""
        return self.backend.tcp_pose(self._check_q(q))

    def _check_q(self, q: np.ndarray) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape != (7,) or not np.isfinite(q).all():
            raise ControllerError(f"joint configuration must be 7 finite values, got {q!r}")
        return q

    def solve_velocity(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray, hard_tcp: bool = False
    ) -> np.ndarray:
        """Solve the QP for joint velocities [rad/s] toward a TCP target.

        Args:
            q: current arm configuration [rad] (7,).
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

        Where no such step exists (the QP is infeasible, e.g. joints pinned at their limits
        with the TCP pose held), the fallback is to hold ``q``: the reset ends there and the
        TCP keeps its pose, instead of a ``ControllerError``.
        """
        try:
            velocity = self.solve_velocity(q, tcp_pos, tcp_rot, hard_tcp=True)
        except InfeasibleQPError:
            return self._check_q(q).copy()
        return self._integrate(np.asarray(q, dtype=float), velocity)


def joint_reset_controller(config: IKConfig | None = None) -> DiffIKController:
    """A controller tuned for joint reset: the posture task dominates in the null space."""
    base = config or IKConfig()
    return DiffIKController(replace(base, posture_cost=1.0, gain=0.5))


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
