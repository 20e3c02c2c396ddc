"""The IK's kinematic backends (``mink``, ``pinocchio``) and the QP composition they share.

Each backend computes the TCP frame task's error and Jacobian on its own model of the arm
(``robot_model``); ``Backend.build_qp`` composes the QP of ``control.ik`` from its lists
of tasks and limits (``control.ik_tasks``) for an arm of any number of joints, so both
backends build the same QP by construction.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
import qpsolvers

from osg_control.control.description import RobotDescription
from osg_control.control.ik_tasks import (
    ConfigurationLimit,
    IKState,
    Limit,
    PostureTask,
    ResidualTask,
    Task,
    VelocityLimit,
    compose_qp,
    constant_diagonal,
)
from osg_control.control.qp import SOLVERS
from osg_control.control.robot_model import pinocchio_arm, robot_spec
from osg_control.errors import ControllerError

BACKEND_NAMES: tuple[str, ...] = ("mink", "pinocchio")
"""The kinematic backends (``BACKENDS``' keys)."""


@dataclass(frozen=True)
class IKConfig:
    """Weights, gains and limits of the differential-IK QP.

    Attributes:
        backend: ``"mink"`` (MuJoCo model) or ``"pinocchio"`` (Pinocchio on the URDF).
        solver: the QP solver: ``"daqp"`` (default) or ``"osqp"``.
        dt: integration step of one solve [s] (the env's control period).
        position_cost: TCP position task weight [1/m]: one for the three axes, or one per
            axis of the TCP frame (x, y, z), as mink's and Pink's ``FrameTask`` take it.
        orientation_cost: TCP orientation task weight [1/rad], one or one per TCP axis: an
            arm with fewer than six joints relaxes what it cannot hold (e.g. ``(0.5, 0.5,
            0.0)`` frees the rotation about the approach axis).
        posture_cost: posture task weight toward ``posture`` [1/rad] (keep it low).
        gain: task gain in (0, 1]: the fraction of the error to remove in one step.
        lm_damping: Levenberg-Marquardt damping of the frame task (unitless).
        damping: Tikhonov regularisation of the QP (unitless).
        limit_gain: configuration-limit gain in (0, 1] (how fast limits may be approached).
        velocity_scale: fraction of the robot's joint velocity limits allowed.
        posture: nominal arm configuration [rad]; None: the robot's home posture.
        osqp_eps: OSQP's absolute and relative tolerance (only with ``solver="osqp"``).
    """

    backend: str = "mink"
    solver: str = "daqp"
    dt: float = 0.05
    position_cost: float | tuple[float, float, float] = 1.0
    orientation_cost: float | tuple[float, float, float] = 0.5
    posture_cost: float = 1e-3
    gain: float = 1.0
    lm_damping: float = 1e-6
    damping: float = 1e-9
    limit_gain: float = 0.95
    velocity_scale: float = 1.0
    posture: tuple[float, ...] | None = None
    osqp_eps: float = 1e-9

    def __post_init__(self) -> None:
        if self.backend not in BACKEND_NAMES:
            raise ControllerError(
                f"unknown IK backend {self.backend!r}; known: {sorted(BACKEND_NAMES)}"
            )
        if self.solver not in SOLVERS:
            raise ControllerError(f"unknown QP solver {self.solver!r}; supported: {SOLVERS}")
        if self.solver not in qpsolvers.available_solvers:
            raise ControllerError(
                f"QP solver {self.solver!r} is not installed; available: "
                f"{qpsolvers.available_solvers}"
            )
        if not (0.0 < self.gain <= 1.0 and 0.0 < self.limit_gain <= 1.0 and self.dt > 0):
            raise ControllerError("IKConfig: gain and limit_gain must be in (0, 1], dt > 0")
        for name in ("position_cost", "orientation_cost"):
            axis_costs(name, getattr(self, name))

    @property
    def frame_cost(self) -> np.ndarray:
        """The TCP task's six weights (position axes, then orientation axes)."""
        position = axis_costs("position_cost", self.position_cost)
        return np.concatenate([position, axis_costs("orientation_cost", self.orientation_cost)])


def axis_costs(name: str, cost: float | tuple[float, ...]) -> np.ndarray:
    """A frame task weight as its three per-axis values.

    Raises:
        ControllerError: not one or three finite numbers >= 0.
    """
    try:
        values = np.atleast_1d(np.asarray(cost, dtype=float))
    except (TypeError, ValueError):
        values = np.array([np.nan])
    if values.shape not in ((1,), (3,)) or not (np.isfinite(values).all() and values.min() >= 0):
        raise ControllerError(
            f"IKConfig.{name} must be one or three finite numbers >= 0, got {cost!r}"
        )
    return np.broadcast_to(values, (3,)).copy()


class FrameTask(ResidualTask):
    """The TCP frame task: error ``log(T_bt)`` and Jacobian from the backend's
    ``frame_residual`` toward the solve's target, weighted per TCP axis."""

    def residual(self, state: IKState) -> tuple[np.ndarray, np.ndarray]:
        return state.kinematics.frame_residual(state.q, state.target_pos, state.target_rot)


class Backend:
    """Kinematics of the TCP frame task plus the QP composed from the task and limit lists.

    Subclasses implement ``tcp_pose`` and ``frame_residual``; ``build_qp`` is common, so
    all backends build the same QP.

    Args:
        config: the controller's configuration (the default tasks' and limits' weights).
        robot: the arm's description.
        tasks: costs added to the defaults (``control.ik_tasks``).
        limits: bounds on ``dq`` added to the defaults.

    Attributes:
        config: the controller's configuration.
        robot: the arm's description.
        lower: joint lower limits [rad] (n,).
        upper: joint upper limits [rad] (n,).
        velocity_limit: joint velocity limits [rad/s] (n,), the robot's times
            ``velocity_scale``.
        tcp_task: the TCP frame task (an equality in a joint reset).
        tasks: every cost: ``tcp_task``, the posture task toward ``posture``, then
            ``tasks``.
        limits: every bound: joint positions (gain ``limit_gain``), joint velocities, then
            ``limits``.

    Raises:
        ControllerError: a posture, task or limit sized for another number of joints.
    """

    def __init__(
        self,
        config: IKConfig,
        robot: RobotDescription,
        tasks: Sequence[Task] = (),
        limits: Sequence[Limit] = (),
    ) -> None:
        n = robot.n_joints
        posture = robot.home_q if config.posture is None else config.posture
        if len(posture) != n:
            raise ControllerError(
                f"IKConfig: posture has {len(posture)} values, robot {robot.name!r} has {n} joints"
            )
        self.config = config
        self.robot = robot
        self.n = n
        self.lower = np.array(robot.arm.lower, dtype=float)
        self.upper = np.array(robot.arm.upper, dtype=float)
        self.velocity_limit = np.array(robot.arm.velocity) * config.velocity_scale
        self.posture = np.asarray(posture, dtype=float)
        """The posture task's target [rad] (n,)."""
        self.tcp_task = FrameTask(config.frame_cost, config.gain, config.lm_damping)
        posture_task = PostureTask(self.posture, config.posture_cost, config.gain)
        self.tasks: list[Task] = [self.tcp_task, posture_task, *tasks]
        self.limits: list[Limit] = [
            ConfigurationLimit(self.lower, self.upper, config.limit_gain),
            VelocityLimit(self.velocity_limit, config.dt),
            *limits,
        ]
        for task in self.tasks:
            task.check(n)
        for limit in self.limits:
            limit.check(n)
        # The objective without the frame task when it is held as an equality (joint reset).
        self._reset_tasks = [task for task in self.tasks if task is not self.tcp_task]
        self._diagonal = constant_diagonal(self.tasks, config.damping)
        self._reset_diagonal = constant_diagonal(self._reset_tasks, config.damping)
        self._load()

    def _load(self) -> None:
        """Load the backend's own model of the arm (``robot``, ``config`` set)."""
        raise NotImplementedError

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """TCP position [m] and rotation matrix in the base frame at ``q``."""
        raise NotImplementedError

    def frame_residual(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """TCP task error ``log(T_bt)`` (6,) and its Jacobian (6, n) at ``q``.

        The error is a body twist in the TCP frame, linear part first.
        """
        raise NotImplementedError

    def build_qp(
        self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray, hard_tcp: bool
    ) -> qpsolvers.Problem:
        """Compose the QP in ``dq = v dt`` at ``q`` toward the target from ``tasks`` and
        ``limits`` (``ik_tasks.compose_qp``).

        Args:
            q: arm configuration [rad] (n,).
            target_pos: TCP target position [m] (3,).
            target_rot: TCP target rotation matrix (3, 3).
            hard_tcp: hold the TCP frame task as an equality constraint (joint reset).

        Returns:
            ``qpsolvers.Problem`` with ``P``, ``q``, box bounds ``lb``/``ub`` and, if
            ``hard_tcp``, the equality ``A dq = b``; no general inequalities.
        """
        state = IKState(q, target_pos, target_rot, self)
        if hard_tcp:
            return compose_qp(
                self._reset_tasks, self.limits, [self.tcp_task], self._reset_diagonal, state
            )
        return compose_qp(self.tasks, self.limits, [], self._diagonal, state)


class MinkBackend(Backend):
    """mink's ``FrameTask`` on the robot's arm-only MuJoCo model."""

    def _load(self) -> None:
        import mink

        robot, config = self.robot, self.config
        self.model = robot_spec(robot, with_gripper=False).compile()
        self.configuration = mink.Configuration(self.model)
        self.mink_task = mink.FrameTask(
            robot.tcp.site,
            "site",
            position_cost=config.position_cost,
            orientation_cost=config.orientation_cost,
            gain=config.gain,
            lm_damping=config.lm_damping,
        )
        # The task's target is this SE3, overwritten in place each step (``set_target``
        # would build and copy a new one every time).
        self._target = mink.SE3(np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
        self.mink_task.transform_target_to_world = self._target
        self._site = self.model.site(robot.tcp.site).id
        self._posed_at = np.full(self.n, np.nan)  # the configuration's q (NaN: none yet)

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
            self.mink_task.compute_error(self.configuration),
            self.mink_task.compute_jacobian(self.configuration),
        )


class PinocchioBackend(Backend):
    """Pink's frame-task formulas, evaluated with Pinocchio on the robot's arm (no MuJoCo).

    ``e = log6(T_bt)`` and ``J = -Jlog6(T_tb) J_b`` as in ``pink.tasks.FrameTask``, computed
    without Pink's per-call ``Configuration`` and ``SE3`` copies.
    """

    def _load(self) -> None:
        import pinocchio as pin

        robot = self.robot
        self.model = pinocchio_arm(robot)
        self.model.velocityLimit = self.velocity_limit.copy()
        self.data = self.model.createData()
        self.frame_id = self.model.getFrameId(robot.tcp.frame)
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


BACKENDS: dict[
    str, Callable[[IKConfig, RobotDescription, Sequence[Task], Sequence[Limit]], Backend]
] = {
    "mink": MinkBackend,
    "pinocchio": PinocchioBackend,
}
