r"""Differential IK for the Panda: one QP per control step, two interchangeable backends.

At each step we solve for joint velocities :math:`v` [rad/s]

.. math::

    \min_v \; \|J_{tcp} v - \tfrac{g}{dt} e_{tcp}\|^2_{W_{tcp}}
            + w_{post} \|v - \tfrac{g}{dt}(q_{home} - q)\|^2
    \quad \text{s.t.} \quad q_{min} \le q + v\,dt \le q_{max},\;
    |v| \le v_{max}

with a TCP frame task and a low-weight posture task, joint position and velocity limits
always enforced. Backends:

- ``mink``: mink on the arm-only MuJoCo model compiled from the URDF (default);
- ``pinocchio``: Pink on the Pinocchio model loaded from the same URDF (no simulator).

Both build the same QP (same task errors ``log(T_bt)`` in the TCP frame, same limits) and
solve it through qpsolvers; ``daqp`` is the default solver, ``osqp`` is supported.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any, Protocol

import mujoco
import numpy as np
import qpsolvers
from scipy.spatial.transform import Rotation

from osg_control.errors import ControllerError
from osg_control.robot import HOME_Q, TCP_FRAME, TCP_SITE, load_pinocchio_arm, panda_spec

SOLVERS: tuple[str, ...] = ("daqp", "osqp")


@dataclass(frozen=True)
class IKConfig:
    """Weights, gains and limits of the differential-IK QP.

    Attributes:
        backend: ``"mink"`` (MuJoCo model) or ``"pinocchio"`` (Pink on the URDF).
        solver: a qpsolvers solver name: ``"daqp"`` (default) or ``"osqp"``.
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


class Backend(Protocol):
    """What a kinematics backend provides to the controller."""

    lower: np.ndarray
    upper: np.ndarray
    velocity_limit: np.ndarray

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """TCP position [m] and rotation matrix in the base frame at ``q``."""
        ...

    def build_qp(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray, hard_tcp: bool
    ) -> qpsolvers.Problem:
        """Assemble the QP at ``q`` toward the target (``hard_tcp``: TCP as an equality)."""
        ...


class MinkBackend:
    """mink on the arm-only MuJoCo model compiled from the URDF."""

    def __init__(self, config: IKConfig) -> None:
        import mink

        self.config = config
        self.model = panda_spec(with_fingers=False).compile()
        self.configuration = mink.Configuration(self.model)
        self.lower = self.model.jnt_range[:, 0].copy()
        self.upper = self.model.jnt_range[:, 1].copy()
        self.velocity_limit = _urdf_velocity_limits() * config.velocity_scale
        self.frame_task = mink.FrameTask(
            TCP_SITE,
            "site",
            position_cost=config.position_cost,
            orientation_cost=config.orientation_cost,
            gain=config.gain,
            lm_damping=config.lm_damping,
        )
        self.posture_task = mink.PostureTask(self.model, cost=config.posture_cost, gain=config.gain)
        self.posture_task.set_target(np.asarray(config.posture))
        names = [self.model.joint(i).name for i in range(self.model.njnt)]
        self.limits = [
            mink.ConfigurationLimit(self.model, gain=config.limit_gain),
            mink.VelocityLimit(self.model, dict(zip(names, self.velocity_limit, strict=True))),
        ]
        self._mink = mink

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.configuration.update(q)
        data = self.configuration.data
        site = self.model.site(TCP_SITE).id
        return data.site_xpos[site].copy(), data.site_xmat[site].reshape(3, 3).copy()

    def build_qp(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray, hard_tcp: bool
    ) -> qpsolvers.Problem:
        self.configuration.update(q)
        self.frame_task.set_target(
            self._mink.SE3.from_rotation_and_translation(
                self._mink.SO3.from_matrix(target_rot), target_pos
            )
        )
        tasks = [self.posture_task] if hard_tcp else [self.frame_task, self.posture_task]
        return self._mink.build_ik(
            self.configuration,
            tasks,
            self.config.dt,
            damping=self.config.damping,
            limits=self.limits,
            constraints=[self.frame_task] if hard_tcp else None,
        )


class PinocchioBackend:
    """Pink on the arm-only Pinocchio model built from the same URDF (runs without MuJoCo)."""

    def __init__(self, config: IKConfig) -> None:
        import pink
        import pinocchio as pin
        from pink.limits import ConfigurationLimit, VelocityLimit

        self.config = config
        self.model = load_pinocchio_arm()
        self.model.velocityLimit = _urdf_velocity_limits() * config.velocity_scale
        self.data = self.model.createData()
        self.lower = self.model.lowerPositionLimit.copy()
        self.upper = self.model.upperPositionLimit.copy()
        self.velocity_limit = self.model.velocityLimit.copy()
        self.frame_id = self.model.getFrameId(TCP_FRAME)
        self.frame_task = pink.FrameTask(
            TCP_FRAME,
            position_cost=config.position_cost,
            orientation_cost=config.orientation_cost,
            lm_damping=config.lm_damping,
            gain=config.gain,
        )
        self.posture_task = pink.PostureTask(cost=config.posture_cost, gain=config.gain)
        self.posture_task.set_target(np.asarray(config.posture))
        self.limits = [
            ConfigurationLimit(self.model, config_limit_gain=config.limit_gain),
            VelocityLimit(self.model),
        ]
        self._pink = pink
        self._pin = pin

    def _configuration(self, q: np.ndarray) -> Any:
        return self._pink.Configuration(self.model, self.data, q, copy_data=False)

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self._pin.framesForwardKinematics(self.model, self.data, q)
        placement = self.data.oMf[self.frame_id]
        return placement.translation.copy(), placement.rotation.copy()

    def build_qp(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray, hard_tcp: bool
    ) -> qpsolvers.Problem:
        configuration = self._configuration(q)
        self.frame_task.set_target(self._pin.SE3(target_rot, target_pos))
        tasks = [self.posture_task] if hard_tcp else [self.frame_task, self.posture_task]
        return self._pink.build_ik(
            configuration,
            tasks,
            self.config.dt,
            damping=self.config.damping,
            limits=self.limits,
            constraints=[self.frame_task] if hard_tcp else None,
        )


BACKENDS: dict[str, Callable[[IKConfig], Backend]] = {
    "mink": MinkBackend,
    "pinocchio": PinocchioBackend,
}


def _urdf_velocity_limits() -> np.ndarray:
    """Per-joint velocity limits [rad/s] read from the URDF (via Pinocchio's parser)."""
    return np.asarray(load_pinocchio_arm().velocityLimit, dtype=float).copy()


def rotation_step(rot: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """Rotate ``rot`` by the world-frame rotation vector ``delta`` [rad]."""
    return np.asarray(Rotation.from_rotvec(delta).as_matrix() @ rot)


def rotation_error(current: np.ndarray, target: np.ndarray) -> np.ndarray:
    """World-frame rotation vector [rad] taking ``current`` to ``target``."""
    return np.asarray(Rotation.from_matrix(target @ current.T).as_rotvec())


class DiffIKController:
    """Turns TCP targets or relative TCP commands into joint position targets.

    Example:
        >>> ik = DiffIKController(IKConfig(backend="mink", solver="daqp"))
        >>> q_next = ik.relative_step(HOME_Q, np.array([0.01, 0, 0, 0, 0, 0]))
    """

    def __init__(self, config: IKConfig | None = None) -> None:
        self.config = config or IKConfig()
        self.backend: Backend = BACKENDS[self.config.backend](self.config)

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics: TCP position [m] and rotation matrix in the base frame."""
        return self.backend.tcp_pose(self._check_q(q))

    def _check_q(self, q: np.ndarray) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape != (7,) or not np.all(np.isfinite(q)):
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
        if not (np.all(np.isfinite(target_pos)) and np.all(np.isfinite(target_rot))):
            raise ControllerError("TCP target must be finite")
        problem = self.backend.build_qp(q, target_pos, target_rot, hard_tcp)
        solution = qpsolvers.solve_problem(problem, solver=self.config.solver)
        if not solution.found or solution.x is None:
            raise ControllerError(
                f"QP solver {self.config.solver!r} found no solution at q={q.round(4)}"
            )
        return np.asarray(solution.x) / self.config.dt  # the QP's unknown is dq = v dt

    def step(self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray) -> np.ndarray:
        """One IK step: the next joint target ``q + v dt`` [rad], clipped to the joint limits."""
        velocity = self.solve_velocity(q, target_pos, target_rot)
        return self._integrate(q, velocity)

    def _integrate(self, q: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        return np.clip(q + velocity * self.config.dt, self.backend.lower, self.backend.upper)

    def relative_step(self, q: np.ndarray, delta: np.ndarray) -> np.ndarray:
        """Apply a relative TCP command ``[dx, dy, dz, da, db, dg]`` ([m], [rad], base frame).

        Returns:
            The next joint position target [rad].
        """
        delta = np.asarray(delta, dtype=float)
        if delta.shape != (6,) or not np.all(np.isfinite(delta)):
            raise ControllerError(f"relative TCP command must be 6 finite values, got {delta!r}")
        pos, rot = self.tcp_pose(q)
        return self.step(q, pos + delta[:3], rotation_step(rot, delta[3:]))

    def reset_step(
        self, q: np.ndarray, tcp_pos: np.ndarray, tcp_rot: np.ndarray
    ) -> np.ndarray:
        """One joint-reset step: move toward the posture while holding the TCP pose fixed."""
        velocity = self.solve_velocity(q, tcp_pos, tcp_rot, hard_tcp=True)
        return self._integrate(q, velocity)


def joint_reset_controller(config: IKConfig | None = None) -> DiffIKController:
    """A controller tuned for joint reset: the posture task dominates in the null space."""
    base = config or IKConfig()
    return DiffIKController(replace(base, posture_cost=1.0, gain=0.5))


def solve_ik(
    controller: DiffIKController,
    q0: np.ndarray,
    target_pos: np.ndarray,
    target_rot: np.ndarray,
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


def quat_to_matrix(quat_wxyz: np.ndarray) -> np.ndarray:
    """Rotation matrix of a ``w, x, y, z`` quaternion (MuJoCo's order)."""
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat_wxyz, dtype=float))
    return mat.reshape(3, 3)
