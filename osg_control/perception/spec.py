"""Named perceptions: which sensors a robot has and how noisy they are.

- ``paper``: the paper's protocol: Gaussian noise ``tcp_noise`` [m] on the perceived TCP
  position, joints and objects exact.
- ``robot``: joint encoders with ``ENCODER_NOISE`` [rad] per joint, the TCP by forward
  kinematics of the perceived joints, finger width with ``FINGER_NOISE`` [m], object
  positions with ``object_noise`` [m] (default 1 cm) and orientations with
  ``OBJECT_ANGLE_NOISE`` [rad] from a simulated pose estimator.
- ``camera``: the ``robot`` perception's encoders and gripper, with the objects a scene's
  fixed cameras locate (``environment.camera_sensing``) from rendered RGB and depth images
  every ``camera_every`` control steps and at every decision point; fields no camera reads
  (e.g. a door's travel) from the ``robot`` pose estimator.
- ``env``: an outside env's own observation (FrankaKitchen-v1: its robot and object noise).
- ``sim``: the simulator's state itself, an oracle (reported as such wherever it is used).

The gripper's force is the gripper motor's own effort (the actuator force the robot drives;
a parallel gripper's controller reports its grasp force the same way), not a fingertip
sensor.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from osg_control.errors import UsageError
from osg_control.json_files import is_json_number

ENCODER_NOISE = 5e-4
"""Joint encoder noise [rad], per joint: about 0.4 mm at the kitchen arm's TCP per joint (its
absolute encoders resolve far finer; the margin stands for calibration and backlash)."""
TCP_PER_ENCODER = 0.7
"""The TCP position's noise [m] per axis per radian of encoder noise, through forward
kinematics: measured 0.31-0.40 mm per axis at ``ENCODER_NOISE`` (2000 readings of the
kitchen arm held at a start), about 0.7 m/rad."""
FINGER_NOISE = 5e-4
"""Finger width noise [m] (the gripper's own width reading)."""
OBJECT_NOISE = 0.01
"""Default object position noise [m] of the ``robot`` perception's pose estimator."""
OBJECT_ANGLE_NOISE = 0.05
"""Object orientation noise [rad] (about 3 degrees) of the ``robot`` pose estimator."""
MAX_NOISE = 1.0
"""The largest noise level [m, or rad for angles] a perception takes: a metre of position
noise already places every object anywhere in the scene; 1e300 made the observations
non-finite."""
CAMERA_EVERY = 10
"""Control steps between two camera renders outside decision points (2 Hz at 20 Hz)."""
CAMERA_SIZE = (320, 240)
"""Camera image width and height [px]."""
MAX_CAMERA_COUNT = 8192
"""The largest camera rate (control steps between renders) and image side [px] taken."""
PERCEPTIONS: dict[str, str] = {
    "paper": "noise on the perceived TCP position, objects exact (the paper's protocol)",
    "robot": "joint encoders, TCP by forward kinematics, noisy object pose estimator",
    "camera": "joint encoders, TCP by forward kinematics, objects from fixed cameras' images",
    "env": "an outside env's own observation, with its own noise",
    "sim": "the simulator's state (an oracle)",
}
"""The known perceptions and what each perceives."""
SIMULATED_PERCEPTIONS: tuple[str, ...] = ("paper", "robot", "sim")
"""The perceptions an ``ArmEnv`` simulates (``env`` is an outside env's own observation),
also a ``Domain``'s default ``perceptions``."""


@dataclass(frozen=True)
class PerceptionSpec:
    """What a robot perceives and with what noise.

    Attributes:
        name: one of ``PERCEPTIONS``.
        tcp_noise: Gaussian noise on the perceived TCP position [m] (``paper``).
        joint_noise: encoder noise [rad] per arm joint (``robot``: TCP by forward
            kinematics of the noisy joints).
        finger_noise: noise on the perceived finger width [m].
        object_noise: noise on object positions [m] (the pose estimator's).
        object_angle_noise: noise on object orientations and joint angles [rad].
        camera_every: control steps between camera renders outside decision points
            (``camera``; 0 elsewhere).
        image_width, image_height: the camera images' size [px] (``camera``).
    """

    name: str = "paper"
    tcp_noise: float = 0.0
    joint_noise: float = 0.0
    finger_noise: float = 0.0
    object_noise: float = 0.0
    object_angle_noise: float = 0.0
    camera_every: int = 0
    image_width: int = 0
    image_height: int = 0

    def __post_init__(self) -> None:
        if self.name not in PERCEPTIONS:
            raise UsageError(
                f"unknown perception {self.name!r}; known perceptions: {', '.join(PERCEPTIONS)}"
            )
        for field_name in (
            "tcp_noise",
            "joint_noise",
            "finger_noise",
            "object_noise",
            "object_angle_noise",
        ):
            value = getattr(self, field_name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise UsageError(f"perception {field_name} must be a number, got {value!r}")
            if not (math.isfinite(value) and 0 <= value <= MAX_NOISE):
                raise UsageError(
                    f"perception {field_name} must be finite and in [0, {MAX_NOISE:g}], "
                    f"got {value!r}"
                )
        sizes = (self.camera_every, self.image_width, self.image_height)
        if self.name == "camera" and not all(
            isinstance(v, int) and 1 <= v <= MAX_CAMERA_COUNT for v in sizes
        ):
            raise UsageError(
                f"the camera perception needs a rate and an image size in [1, "
                f"{MAX_CAMERA_COUNT}], got camera_every={self.camera_every}, "
                f"image {self.image_width}x{self.image_height}"
            )

    @property
    def exact(self) -> bool:
        """No noise anywhere: the percept equals what the simulator's state gives."""
        return not any(
            (
                self.tcp_noise,
                self.joint_noise,
                self.finger_noise,
                self.object_noise,
                self.object_angle_noise,
            )
        )

    @property
    def tcp_position_noise(self) -> float:
        """The perceived TCP position's noise [m] per axis: the paper's ``tcp_noise`` and
        the encoders' through forward kinematics (``TCP_PER_ENCODER``), together."""
        return math.hypot(self.tcp_noise, TCP_PER_ENCODER * self.joint_noise)

    def to_dict(self) -> dict[str, Any]:
        """The name and parameters, for a command's ``--json``."""
        return asdict(self)


def perception_spec(
    name: str = "paper", noise: float = 0.0, object_noise: float | None = None
) -> PerceptionSpec:
    """The named perception with the command line's noise levels.

    Args:
        name: ``paper``, ``robot``, ``camera``, ``env`` or ``sim``.
        noise: the paper's TCP position noise [m] (``paper``; refused elsewhere when > 0).
        object_noise: the pose estimator's position noise [m] (``robot``, and ``camera``'s
            fields no camera reads; default ``OBJECT_NOISE``).

    Raises:
        UsageError: an unknown name (the known ones listed), a noise that is not a
            finite number in [0, ``MAX_NOISE``], or a noise the perception has no sensor for.
    """
    if name not in PERCEPTIONS:
        raise UsageError(
            f"unknown perception {name!r}; known perceptions: {', '.join(PERCEPTIONS)}"
        )
    for label, value in (("--noise", noise), ("--object-noise", object_noise)):
        if value is not None and not (
            is_json_number(value) and math.isfinite(value) and 0 <= value <= MAX_NOISE
        ):
            raise UsageError(
                f"{label} must be finite and in [0, {MAX_NOISE:g}] (>= 0 and at most "
                f"{MAX_NOISE:g}), got {value!r}"
            )
    if name in ("robot", "camera"):
        if noise:
            raise UsageError(
                f"--noise is the paper protocol's TCP noise; the {name} perception takes the TCP "
                "from its joint encoders (use --perception paper, or --object-noise)"
            )
        camera = {}
        if name == "camera":
            camera = {
                "camera_every": CAMERA_EVERY,
                "image_width": CAMERA_SIZE[0],
                "image_height": CAMERA_SIZE[1],
            }
        return PerceptionSpec(
            name,
            joint_noise=ENCODER_NOISE,
            finger_noise=FINGER_NOISE,
            object_noise=OBJECT_NOISE if object_noise is None else object_noise,
            object_angle_noise=OBJECT_ANGLE_NOISE,
            **camera,
        )
    if object_noise:
        raise UsageError(f"--object-noise applies to the robot perception and camera, not {name!r}")
    if name == "paper":
        return PerceptionSpec("paper", tcp_noise=noise)
    if noise and name == "sim":
        raise UsageError("the sim perception is the simulator's exact state: no --noise")
    return PerceptionSpec(name, tcp_noise=noise)


def check_supported(spec: PerceptionSpec, supported: tuple[str, ...], domain: str) -> None:
    """Refuse a perception a domain does not support.

    Raises:
        UsageError: naming the domain and the perceptions it supports.
    """
    if spec.name not in supported:
        raise UsageError(
            f"domain {domain!r} does not support perception {spec.name!r}; "
            f"it supports: {', '.join(supported)}"
        )
