"""The env's Panda as the adapter drives it: its robot description
(``robots.franka_kitchen_panda``, registered as ``franka-kitchen-panda``) checked against the
env it wraps, the core's differential IK (``control.ik``) built from that description, and how
the env's own servos turn the IK's joint velocity into the env's 9-D action.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cache
from typing import Any, ClassVar

import mujoco
import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.control.ik import DiffIKController, IKConfig
from osg_control.control.robot_model import robot_spec
from osg_control.environment.options import Bounds, check_fields
from osg_control.errors import DomainError, EnvOptionError
from osg_control.perception.spec import PerceptionSpec

ROBOT = "franka-kitchen-panda"
"""The registered robot this domain's env drives (``robots.franka_kitchen_panda``)."""
JOINT_RESET_POSTURE_COST = 0.05
"""The posture task's weight in the joint reset (``franka.setup.joint_reset``): strong enough
to pull the joints home within a few steps, under the TCP task that holds the pose."""


@dataclass(frozen=True)
class FrankaConfig:
    """Options of the adapter.

    Attributes:
        position_cost: the IK's TCP position weight [1/m] (``control.ik.IKConfig``).
        orientation_cost: its orientation weight [1/rad].
        posture_cost: weight of the posture task toward the env's reset posture.
        limit_gain: the IK's joint-limit gain.
        perception: what the adapter perceives (``franka.perception``): ``env`` (the
            env's own observation, the default) or ``sim`` (the simulator, an oracle);
            ``tcp_noise`` adds the paper's Gaussian noise [m] to the perceived TCP position
            (``env`` only: ``sim`` is exact).

    Raises:
        EnvOptionError: a field outside its range (``BOUNDS``), or a perception the domain
            does not support, named.
    """

    position_cost: float = 1.0
    orientation_cost: float = 0.5
    posture_cost: float = 1e-3
    limit_gain: float = 0.5
    perception: PerceptionSpec = field(default_factory=lambda: PerceptionSpec("env"))

    BOUNDS: ClassVar[dict[str, Bounds]] = {
        "position_cost": Bounds(),
        "orientation_cost": Bounds(),
        "posture_cost": Bounds(),
        "limit_gain": Bounds(high=1.0, open_low=True),
    }
    """The range of each numeric field."""

    def __post_init__(self) -> None:
        from osg_control.franka.perception import PERCEPTIONS

        check_fields(self, self.BOUNDS)
        spec = self.perception
        if not isinstance(spec, PerceptionSpec):
            raise EnvOptionError(f"FrankaConfig.perception must be a PerceptionSpec, got {spec!r}")
        if spec.name not in PERCEPTIONS:
            raise EnvOptionError(
                f"FrankaConfig.perception: franka-kitchen supports the perceptions "
                f"{', '.join(PERCEPTIONS)}, not {spec.name!r}"
            )
        noisy = {
            k: getattr(spec, k)
            for k in ("joint_noise", "finger_noise", "object_noise", "object_angle_noise")
            if getattr(spec, k)
        }
        if noisy or (spec.name == "sim" and spec.tcp_noise):
            raise EnvOptionError(
                f"FrankaConfig.perception {spec.name!r}: the env's own observation carries "
                f"the robot's and the objects' noise (its robot_noise_ratio and "
                f"object_noise_ratio) and 'sim' is exact; only 'env' takes tcp_noise, got "
                f"{ {**noisy, 'tcp_noise': spec.tcp_noise} }"
            )

    def ik_config(self, dt: float, posture: np.ndarray) -> IKConfig:
        """The core IK's configuration: these weights, the env's step ``dt`` [s], the env's
        reset ``posture``, and no joint-speed box: the servo command scales the whole joint
        vector into the action (``ServoCommand``), which keeps the TCP's direction where a
        per-joint bound would turn it."""
        return IKConfig(
            dt=dt,
            position_cost=self.position_cost,
            orientation_cost=self.orientation_cost,
            posture_cost=self.posture_cost,
            limit_gain=self.limit_gain,
            posture=tuple(float(v) for v in posture),
            velocity_scale=math.inf,
        )


def arm_controllers(
    robot: RobotDescription, config: FrankaConfig, dt: float, posture: np.ndarray
) -> tuple[DiffIKController, DiffIKController]:
    """The core IK on ``robot`` for the adapter's steps, and the same IK with the joint
    reset's posture weight (``JOINT_RESET_POSTURE_COST``)."""
    ik_config = config.ik_config(dt, posture)
    reset = replace(ik_config, posture_cost=JOINT_RESET_POSTURE_COST)
    return DiffIKController(robot, ik_config), DiffIKController(robot, reset)


def check_kitchen_robot(kitchen: Any, robot: RobotDescription) -> None:
    """Hold the env the adapter wraps against ``robot``: the joint limits it enforces, its
    servo gains and joint damping, its finger servos' gain and its control period.

    Raises:
        DomainError: naming what differs.
    """
    from osg_control.robots.franka_kitchen_panda import enforced_limits

    model = kitchen.model
    n = robot.n_joints
    lower, upper = enforced_limits(model, kitchen.robot_env.robot_pos_bound[:n])
    kp, damping = servo_gains(model, robot.arm.names)
    fingers = [model.joint(j) for j in robot.gripper.joints]
    finger_kp = [float(model.actuator_gainprm[_actuator(model, j.id), 0]) for j in fingers]
    checks: dict[str, tuple[Any, Any]] = {
        "joint lower limits": (lower, robot.arm.lower),
        "joint upper limits": (upper, robot.arm.upper),
        "servo kp": (kp, robot.servo.kp),
        "joint damping": (damping, robot.servo.kv),
        "finger servo kp": (finger_kp, [robot.gripper.kp] * len(fingers)),
        "control rate": ([1.0 / float(kitchen.robot_env.dt)], [robot.control_hz]),
    }
    for what, (env_value, described) in checks.items():
        if not np.allclose(env_value, described, rtol=0.0, atol=1e-9):
            raise DomainError(
                f"franka-kitchen: the env's {what} {np.asarray(env_value).tolist()} differ "
                f"from robot {robot.name!r}'s {list(described)}"
            )


def _actuator(model: mujoco.MjModel, joint: int) -> int:
    return next(a for a in range(model.nu) if model.actuator_trnid[a, 0] == joint)


def servo_gains(model: mujoco.MjModel, joints: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Each joint's position servo gain ``kp`` [N m/rad] and its joint damping [N m s/rad]
    in ``model``."""
    ids = [model.joint(name) for name in joints]
    kp = [float(model.actuator_gainprm[_actuator(model, j.id), 0]) for j in ids]
    damping = [float(model.dof_damping[j.dofadr[0]]) for j in ids]
    return np.array(kp), np.array(damping)


def servo_response(robot: RobotDescription, dt: float) -> np.ndarray:
    """The fraction of a step's target offset each arm joint's servo covers in one env step
    of ``dt`` [s].

    The env's arm servos are damping-dominated (``kp`` 870 / 120, joint damping 100 / 10,
    no armature; the description's ``servo.kp`` and ``servo.kv``): ``b dq/dt = kp (ctrl - q)
    - bias``, a first-order lag with time constant ``b / kp`` (0.115 s / 0.083 s), so within
    one 80 ms step a joint covers ``1 - exp(-dt kp / b)`` (about 0.50 / 0.62) of its target
    offset. Dividing each joint's offset by its fraction makes all joints arrive together
    (the Cartesian direction holds).
    """
    kp, damping = np.array(robot.servo.kp), np.array(robot.servo.kv)
    return 1.0 - np.exp(-dt * kp / damping)


@cache
def dynamics_model(robot: RobotDescription) -> mujoco.MjModel:
    """The robot's model with its fingers (``control.robot_model.robot_spec``), compiled
    once and shared read-only: the servo command's bias torques."""
    return robot_spec(robot).compile()


class ServoCommand:
    """IK joint velocity -> the env's 9-D action for this robot's servos: each joint's
    step offset ``v dt`` divided by its servo's one-step response, plus the offset that
    holds the bias torques (``bias / kp``: gravity), scaled as a whole (``scale_to_action``,
    see ``servo_response``); fingers +-1 (closing or opening at full speed).

    Args:
        robot: the env's arm (its servo gains; its joint speed at an action of 1,
            ``arm.velocity``).
        dt: the env's step [s].
    """

    def __init__(self, robot: RobotDescription, dt: float) -> None:
        self.kp = np.array(robot.servo.kp)
        self.fraction = servo_response(robot, dt)
        self.speed = np.array(robot.arm.velocity)
        self.dt = dt
        self._model = dynamics_model(robot)
        self._dynamics = mujoco.MjData(self._model)
        self._arm = np.array([self._model.joint(j).qposadr[0] for j in robot.arm.names])
        self._arm_dof = np.array([self._model.joint(j).dofadr[0] for j in robot.arm.names])

    def bias(self, q: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """The arm's bias torques [N m] (gravity, Coriolis) at joints ``q`` and speeds
        ``qvel`` on the robot's model (the hand and the fingers, at rest, included)."""
        self._dynamics.qpos[self._arm] = q
        self._dynamics.qvel[self._arm_dof] = qvel
        mujoco.mj_forward(self._model, self._dynamics)
        return self._dynamics.qfrc_bias[self._arm_dof].copy()

    def action(self, velocity: np.ndarray, bias: np.ndarray, closed: bool) -> np.ndarray:
        """The env's action for joint velocity ``velocity`` [rad/s] under ``bias`` [N m]."""
        offset = np.asarray(velocity) * self.dt / self.fraction + np.asarray(bias) / self.kp
        finger = -1.0 if closed else 1.0
        arm = scale_to_action(offset, self.dt, self.speed)
        return np.concatenate([arm, [finger, finger]])


def scale_to_action(offset: np.ndarray, dt: float, speed: np.ndarray | float) -> np.ndarray:
    """A joint servo-target offset [rad] -> the env's arm action (the env's target is
    ``observed q + speed * a * dt``, ``speed`` [rad/s] the joint speed of an action of 1),
    scaled as a whole into [-1, 1]."""
    action = np.asarray(offset, dtype=float) / (np.asarray(speed) * dt)
    largest = float(np.abs(action).max()) if action.size else 0.0
    return action / largest if largest > 1.0 else action
