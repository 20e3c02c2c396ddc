"""``RobotDescription``: a robot arm and its gripper as data, for every layer that drives one.

The core never names a robot: it builds the simulated arm, the IK and the sensors from a
description (``control.robot_model``), and a robot module (``osg_control.robots``) is one
instance of it plus the two builders of its models:

- ``ModelSource.mujoco``: a callable returning the robot's bare ``mujoco.MjSpec`` (links,
  joints, geoms, inertias, the gripper's joints and their coupling; no actuators, no TCP
  site, no keyframe: the core adds those from the description);
- ``ModelSource.pinocchio``: a callable returning the arm-only ``pinocchio.Model`` (the
  gripper's joints locked; ``robot_model.reduced_urdf_model`` builds one from a URDF,
  ``mujoco_pinocchio.pinocchio_arm_from_mujoco`` from a compiled MJCF) in
  which ``TcpFrame.frame`` is the TCP.

Tool convention: the TCP frame's z axis points out of the tool (the approach direction)
and its y axis is the fingers' closing direction, so that a domain's orientations (e.g.
``domain.spec.TOP_DOWN_QUAT``) mean the same grasp whatever the arm. A description places
its TCP (``TcpFrame``) in that convention.

Everything checkable from the data alone is checked when a description is built
(``RobotDescriptionError`` naming the robot and the field); what needs the models (the
joints, the TCP's parent body and frame, the gripper's joints and their limits) is
checked by ``robot_model.check_models`` when the registry first loads the robot.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from osg_control.errors import OSGError

Placement = tuple[tuple[float, float, float], tuple[float, float, float, float]]
"""Where a robot's base stands in a scene: a position [m] and an orientation (w, x, y, z)."""
ORIGIN: Placement = ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
"""The scene's origin, not rotated: where a robot stands unless a domain mounts it elsewhere."""

SENSORS: tuple[str, ...] = ("encoders", "finger_width", "grip_force")
"""What an arm may measure of itself: joint encoders (the ``robot`` perception's TCP by
forward kinematics), the gripper's finger width, and the gripper motor's force."""


class RobotDescriptionError(OSGError):
    """A robot description is inconsistent; the message names the robot and the field."""


@dataclass(frozen=True)
class ModelSource:
    """How to build the robot's two models (see the module docstring).

    Attributes:
        mujoco: () -> the robot's bare ``mujoco.MjSpec``, gripper included.
        pinocchio: () -> the arm-only ``pinocchio.Model`` (gripper locked).
    """

    mujoco: Callable[[], Any]
    pinocchio: Callable[[], Any]


@dataclass(frozen=True)
class ArmJoints:
    """The arm's joints, base to tip, with their limits (each tuple one value per joint).

    Attributes:
        names: joint names in both models.
        lower, upper: position limits [rad].
        velocity: speed limits [rad/s] (the IK's bound and the drive's cap).
        effort: torque limits [N m] (the drive's force range).
        armature: reflected rotor inertia [kg m^2] added in the MuJoCo model.
    """

    names: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    velocity: tuple[float, ...]
    effort: tuple[float, ...]
    armature: tuple[float, ...]


@dataclass(frozen=True)
class ServoGains:
    """The arm's joint position servos: stiffness ``kp`` [N m/rad] and damping ``kv``
    [N m s/rad] per joint (``control.servo``'s speed-capped drive)."""

    kp: tuple[float, ...]
    kv: tuple[float, ...]


@dataclass(frozen=True)
class TcpFrame:
    """The tool centre point, in the tool convention of the module docstring.

    Attributes:
        body: the MuJoCo body the TCP site is attached to.
        pos: the site's position in ``body`` [m].
        quat: the site's orientation in ``body`` (``w, x, y, z``).
        frame: the Pinocchio frame that is the same TCP.
        site: the MuJoCo site's name.
    """

    body: str
    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float]
    frame: str
    site: str = "tcp"


@dataclass(frozen=True)
class Gripper:
    """A position-driven parallel gripper.

    Attributes:
        joints: its joints; the first is the one the actuator drives, the others follow it
            (the model's own coupling, e.g. an equality).
        bodies: the finger bodies (what a grasp touches; removed in the arm-only model).
        open_position: the driven joint's position when open [m] (closed is 0).
        kp, kv: the actuator's position gain [N/m] and damping [N s/m].
        force: the actuator's force limit [N]: the grip force, and its readout's range.
        armature, damping: each finger joint's reflected inertia [kg] and damping [N s/m].
        width_scale: the finger width [m] per unit of the joints' summed positions.
    """

    joints: tuple[str, ...]
    bodies: tuple[str, ...]
    open_position: float
    kp: float
    kv: float
    force: float
    armature: float = 0.0
    damping: float = 0.0
    width_scale: float = 1.0

    @property
    def max_opening(self) -> float:
        """The distance between the fingers when open [m]."""
        return self.width_scale * self.open_position * len(self.joints)


@dataclass(frozen=True)
class RobotDescription:
    """One robot arm with its gripper (see the module docstring).

    Attributes:
        name: registry key (``osg --robot NAME``).
        summary: one line for humans.
        model: the builders of its MuJoCo and Pinocchio models.
        arm: the arm's joints and limits.
        servo: the joint servos' gains.
        tcp: the tool centre point.
        gripper: the gripper.
        home_q: the home posture [rad], one value per arm joint (the IK's posture target).
        control_hz: the rate of the arm's control loop [Hz].
        sensors: what it measures of itself (``SENSORS``).
        gravity_compensation: whether the drives cancel the links' weight.
        mount: where its base stands in the scene it is built into. A domain declares it
            (``Domain.mounts``) and ``mounted`` sets it: both models are built with the
            base there, so the IK, the TCP readouts and the resets work in scene
            coordinates. The default is the scene's origin.
    """

    name: str
    summary: str
    model: ModelSource
    arm: ArmJoints
    servo: ServoGains
    tcp: TcpFrame
    gripper: Gripper
    home_q: tuple[float, ...]
    control_hz: float = 20.0
    sensors: tuple[str, ...] = SENSORS
    gravity_compensation: bool = True
    mount: Placement = ORIGIN

    def __post_init__(self) -> None:
        check_description(self)

    @property
    def n_joints(self) -> int:
        """The number of arm joints."""
        return len(self.arm.names)

    @property
    def redundant(self) -> bool:
        """Whether the arm has a null space under a 6-D TCP task (more than six joints):
        only then can a joint reset move the joints with the TCP held."""
        return self.n_joints > 6

    def substeps(self, timestep: float) -> int:
        """Physics substeps of ``timestep`` [s] in one control step."""
        return round(1.0 / (self.control_hz * timestep))

    def to_dict(self) -> dict[str, Any]:
        """The description's data (not its builders), for ``osg robots --json``."""
        arm = self.arm
        return {
            "name": self.name,
            "summary": self.summary,
            "joints": list(arm.names),
            "lower": list(arm.lower),
            "upper": list(arm.upper),
            "velocity": list(arm.velocity),
            "effort": list(arm.effort),
            "home_q": list(self.home_q),
            "tcp": {"body": self.tcp.body, "frame": self.tcp.frame, "site": self.tcp.site},
            "gripper": {
                "joints": list(self.gripper.joints),
                "max_opening": self.gripper.max_opening,
                "force": self.gripper.force,
            },
            "control_hz": self.control_hz,
            "sensors": list(self.sensors),
            "redundant": self.redundant,
            "mount": {"position": list(self.mount[0]), "quat": list(self.mount[1])},
        }


def mounted(robot: RobotDescription, mount: Placement) -> RobotDescription:
    """``robot`` with its base at ``mount`` in the scene (checked: ``RobotDescriptionError``
    for a non-finite position or a quaternion that is not a unit one)."""
    return replace(robot, mount=(tuple(mount[0]), tuple(mount[1])))  # type: ignore[arg-type]


def _fail(robot: str, field: str, message: str) -> RobotDescriptionError:
    return RobotDescriptionError(f"robot {robot!r}: field {field!r}: {message}")


def _finite(values: tuple[float, ...]) -> bool:
    return all(isinstance(v, int | float) and math.isfinite(v) for v in values)


def check_description(robot: RobotDescription) -> None:
    """The data-only checks of a description (module docstring).

    Raises:
        RobotDescriptionError: naming the robot and the field at fault.
    """
    name, arm = robot.name, robot.arm
    if not name or not arm.names:
        raise _fail(name, "arm.names" if name else "name", "must not be empty")
    if len(set(arm.names)) != len(arm.names):
        raise _fail(name, "arm.names", f"repeats a joint: {list(arm.names)}")
    n = len(arm.names)
    per_joint = {
        "arm.lower": arm.lower,
        "arm.upper": arm.upper,
        "arm.velocity": arm.velocity,
        "arm.effort": arm.effort,
        "arm.armature": arm.armature,
        "servo.kp": robot.servo.kp,
        "servo.kv": robot.servo.kv,
        "home_q": robot.home_q,
    }
    for field, values in per_joint.items():
        if len(values) != n:
            raise _fail(name, field, f"has {len(values)} values for {n} arm joints")
        if not _finite(values):
            raise _fail(name, field, f"must be finite numbers, got {list(values)}")
    for field in ("arm.velocity", "arm.effort", "servo.kp", "servo.kv"):
        if min(per_joint[field]) <= 0:
            raise _fail(name, field, f"must be positive, got {list(per_joint[field])}")
    if min(arm.armature) < 0:
        raise _fail(name, "arm.armature", f"must be >= 0, got {list(arm.armature)}")
    for joint, lo, hi, q in zip(arm.names, arm.lower, arm.upper, robot.home_q, strict=True):
        if not lo < hi:
            raise _fail(name, "arm.lower", f"joint {joint!r}: lower {lo} is not below upper {hi}")
        if not lo <= q <= hi:
            raise _fail(name, "home_q", f"joint {joint!r}: {q} is outside [{lo}, {hi}]")
    _check_tcp(robot)
    _check_gripper(robot)
    _check_mount(robot)
    if not (math.isfinite(robot.control_hz) and robot.control_hz > 0):
        raise _fail(name, "control_hz", f"must be positive, got {robot.control_hz}")
    unknown = sorted(set(robot.sensors) - set(SENSORS))
    if unknown:
        raise _fail(name, "sensors", f"unknown {unknown}; known sensors: {', '.join(SENSORS)}")


def _check_tcp(robot: RobotDescription) -> None:
    tcp = robot.tcp
    if not (tcp.body and tcp.frame and tcp.site):
        raise _fail(robot.name, "tcp", "needs a body, a Pinocchio frame and a site name")
    if len(tcp.pos) != 3 or len(tcp.quat) != 4 or not _finite((*tcp.pos, *tcp.quat)):
        raise _fail(robot.name, "tcp", "pos must be 3 and quat 4 finite numbers")
    if abs(math.fsum(v * v for v in tcp.quat) - 1.0) > 1e-6:
        raise _fail(robot.name, "tcp.quat", f"must be a unit quaternion, got {tcp.quat}")


def _check_gripper(robot: RobotDescription) -> None:
    gripper = robot.gripper
    if not gripper.joints or not gripper.bodies:
        raise _fail(robot.name, "gripper", "needs its joints and finger bodies")
    if set(gripper.joints) & set(robot.arm.names):
        raise _fail(robot.name, "gripper.joints", "shares a joint with the arm")
    values = (gripper.open_position, gripper.kp, gripper.kv, gripper.force, gripper.width_scale)
    if not _finite(values) or min(values) <= 0:
        raise _fail(
            robot.name,
            "gripper",
            "open_position, kp, kv, force and width_scale must be positive and finite: it "
            f"cannot be driven open and shut, got {values}",
        )
    if (
        not _finite((gripper.armature, gripper.damping))
        or min(gripper.armature, gripper.damping) < 0
    ):
        raise _fail(robot.name, "gripper", "armature and damping must be >= 0")


def _check_mount(robot: RobotDescription) -> None:
    position, quat = robot.mount
    if len(position) != 3 or len(quat) != 4 or not _finite((*position, *quat)):
        raise _fail(
            robot.name, "mount", f"needs 3 position and 4 quaternion numbers: {robot.mount}"
        )
    if abs(math.fsum(v * v for v in quat) - 1.0) > 1e-6:
        raise _fail(robot.name, "mount", f"must hold a unit quaternion, got {quat}")
