"""The env's Panda as the adapter's IK sees it: an arm-only model compiled from the env's own
MJCF, the joint limits the env enforces, mink's differential IK on it, and how the env's
servos turn an action into motion.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field
from typing import Any, ClassVar

import mujoco
import numpy as np

from osg_control.environment.options import Bounds, check_fields
from osg_control.errors import DomainError, EnvOptionError
from osg_control.perception.spec import PerceptionSpec

ARM_JOINTS = tuple(f"robot:panda0_joint{i}" for i in range(1, 8))
FINGER_JOINTS = ("robot:panda0_finger_joint1", "robot:panda0_finger_joint2")
TCP_SITE = "end_effector"
ROBOT_ROOT = "panda0_link0"
SHOULDER = (0.0, 0.0, 2.133)
"""The arm's shoulder (``panda0_link2``, joint 2) in the env's frame: the base stands at
(0, 0, 1.8), the shoulder 0.333 m above it."""
REACH = 0.855
"""The arm's reach [m] from its shoulder: no TCP target farther away can be reached."""
ACTION_SCALE = 2.0
"""The env's joint speed [rad/s] for an action of 1 (``FrankaRobot.act_rng``)."""
MODEL_FILE = "envs/assets/kitchen_franka/kitchen_assets/kitchen_env_model.xml"


@dataclass(frozen=True)
class FrankaConfig:
    """Options of the adapter.

    Attributes:
        position_cost: mink frame task position weight [1/m].
        orientation_cost: its orientation weight [1/rad].
        posture_cost: weight of the posture task toward the env's reset posture.
        limit_gain: mink configuration-limit gain.
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


def model_path() -> str:
    """The library's kitchen MJCF."""
    import gymnasium_robotics

    return os.path.join(os.path.dirname(gymnasium_robotics.__file__), MODEL_FILE)


def env_joint_limits(kitchen: Any) -> tuple[np.ndarray, np.ndarray]:
    """The arm's joint limits as the env enforces them: MJCF ``range``, actuator
    ``ctrlrange`` and ``franka_config.xml``'s ``pos_bound``, intersected. (7,), (7,)."""
    model = kitchen.model
    lower, upper = [], []
    for i, name in enumerate(ARM_JOINTS):
        joint = model.joint(name)
        act = next(a for a in range(model.nu) if model.actuator_trnid[a, 0] == joint.id)
        bounds = np.array([joint.range, model.actuator_ctrlrange[act]])
        pos_bound = kitchen.robot_env.robot_pos_bound[i]
        lower.append(max(bounds[:, 0].max(), pos_bound[0]))
        upper.append(min(bounds[:, 1].min(), pos_bound[1]))
    return np.array(lower), np.array(upper)


def build_arm_model(kitchen: Any) -> mujoco.MjModel:
    """An arm-only model (7 joints, the ``end_effector`` site) from the env's own MJCF,
    placed where the env's robot stands, with the env's joint limits."""
    spec = mujoco.MjSpec.from_file(model_path())
    root = spec.body(ROBOT_ROOT)
    arm = mujoco.MjSpec()
    frame = arm.worldbody.add_frame()
    parent = int(kitchen.model.body_parentid[kitchen.model.body(ROBOT_ROOT).id])
    placed = mujoco.MjData(kitchen.model)
    mujoco.mj_kinematics(kitchen.model, placed)
    frame.pos = placed.xpos[parent].copy()
    frame.quat = placed.xquat[parent].copy()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frame.attach_body(root, "", "")
    for actuator in list(arm.actuators):
        arm.delete(actuator)
    for name in FINGER_JOINTS:
        arm.delete(arm.joint(name))
    lower, upper = env_joint_limits(kitchen)
    for name, lo, hi in zip(ARM_JOINTS, lower, upper, strict=True):
        joint = arm.joint(name)
        joint.range = [lo, hi]
        joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = arm.compile()
    if model.nq != 7:
        raise DomainError(f"franka-kitchen: the arm model has {model.nq} joints, expected 7")
    return model


class ArmIK:
    """mink differential IK on the arm-only model: a TCP pose target -> joint velocity."""

    def __init__(self, model: mujoco.MjModel, config: FrankaConfig, posture: np.ndarray) -> None:
        import mink

        self.mink = mink
        self.model = model
        self.configuration = mink.Configuration(model)
        self.frame = mink.FrameTask(
            TCP_SITE,
            "site",
            position_cost=config.position_cost,
            orientation_cost=config.orientation_cost,
            lm_damping=1e-6,
        )
        self.posture = mink.PostureTask(model, cost=config.posture_cost)
        self.posture.set_target(np.asarray(posture, dtype=float))
        self.limits = [mink.ConfigurationLimit(model, gain=config.limit_gain)]
        self.lower = model.jnt_range[:, 0].copy()
        self.upper = model.jnt_range[:, 1].copy()
        self._dynamics = mujoco.MjData(model)

    def bias(self, q: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """The arm's bias torques [N m] (gravity, Coriolis) at joints ``q`` and speeds
        ``qvel`` on the arm model (the hand's mass included, the fingers welded)."""
        self._dynamics.qpos[:] = q
        self._dynamics.qvel[:] = qvel
        mujoco.mj_forward(self.model, self._dynamics)
        return self._dynamics.qfrc_bias.copy()

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """TCP position and rotation matrix at arm joints ``q``."""
        self.configuration.update(np.asarray(q, dtype=float))
        data = self.configuration.data
        site = self.model.site(TCP_SITE).id
        return data.site_xpos[site].copy(), data.site_xmat[site].reshape(3, 3).copy()

    def velocity(
        self,
        q: np.ndarray,
        position: np.ndarray,
        rotation: np.ndarray,
        dt: float,
        posture_cost: float | None = None,
    ) -> np.ndarray:
        """The joint velocity [rad/s] that moves the TCP to the target pose in ``dt``."""
        mink = self.mink
        q = np.clip(np.asarray(q, dtype=float), self.lower + 1e-6, self.upper - 1e-6)
        self.configuration.update(q)
        self.frame.set_target(
            mink.SE3.from_rotation_and_translation(mink.SO3.from_matrix(rotation), position)
        )
        tasks = [self.frame, self.posture]
        if posture_cost is not None:
            self.posture.set_cost(posture_cost)
        try:
            v = mink.solve_ik(
                self.configuration, tasks, dt, "daqp", damping=1e-9, limits=self.limits
            )
        finally:
            if posture_cost is not None:
                self.posture.set_cost(FrankaConfig.posture_cost)
        return np.asarray(v, dtype=float)


def servo_response(kitchen: Any) -> tuple[np.ndarray, np.ndarray]:
    """Each arm joint's servo gain ``kp`` [N m/rad] and the fraction of a step's target
    offset it covers in one env step.

    The env's arm servos are damping-dominated (``kp`` 870 / 120, joint damping 100 / 10,
    no armature): ``b dq/dt = kp (ctrl - q) - bias``, a first-order lag with time constant
    ``b / kp`` (0.115 s / 0.083 s), so within one 80 ms step a joint covers
    ``1 - exp(-dt kp / b)`` (about 0.50 / 0.62) of its target offset. Dividing each joint's
    offset by its fraction makes all joints arrive together (the Cartesian direction holds).
    """
    model = kitchen.model
    dt = float(kitchen.robot_env.dt)
    kp, fraction = [], []
    for name in ARM_JOINTS:
        joint = model.joint(name)
        act = next(a for a in range(model.nu) if model.actuator_trnid[a, 0] == joint.id)
        gain = float(model.actuator_gainprm[act, 0])
        damping = float(model.dof_damping[joint.dofadr[0]])
        kp.append(gain)
        fraction.append(1.0 - np.exp(-dt * gain / damping) if damping > 0 else 1.0)
    return np.array(kp), np.array(fraction)


class ServoCommand:
    """IK joint velocity -> the env's 9-D action for this robot's servos: each joint's
    step offset ``v dt`` divided by its servo's one-step response, plus the offset that
    holds the bias torques (``bias / kp``: gravity), scaled as a whole (``scale_to_action``,
    see ``servo_response``); fingers +-1 (closing or opening at full speed)."""

    def __init__(self, kitchen: Any) -> None:
        self.kp, self.fraction = servo_response(kitchen)
        self.dt = float(kitchen.robot_env.dt)

    def action(self, velocity: np.ndarray, bias: np.ndarray, closed: bool) -> np.ndarray:
        """The env's action for joint velocity ``velocity`` [rad/s] under ``bias`` [N m]."""
        offset = np.asarray(velocity) * self.dt / self.fraction + np.asarray(bias) / self.kp
        finger = -1.0 if closed else 1.0
        return np.concatenate([scale_to_action(offset, self.dt), [finger, finger]])


def scale_to_action(offset: np.ndarray, dt: float) -> np.ndarray:
    """A joint servo-target offset [rad] -> the env's arm action (the env's target is
    ``observed q + ACTION_SCALE * a * dt``), scaled as a whole into [-1, 1]."""
    action = np.asarray(offset, dtype=float) / (ACTION_SCALE * dt)
    largest = float(np.abs(action).max()) if action.size else 0.0
    return action / largest if largest > 1.0 else action


def rotation_step(rotation: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """Rotate a rotation matrix by a world-frame rotation vector ``delta``."""
    quat = np.zeros(4)
    mujoco.mju_axisAngle2Quat(quat, delta / (np.linalg.norm(delta) + 1e-12), np.linalg.norm(delta))
    step = np.zeros(9)
    mujoco.mju_quat2Mat(step, quat)
    return step.reshape(3, 3) @ rotation
