"""The env's options and fixed facts: ``EnvConfig``, the observation and action sizes and
bounds, the simulated perceptions and the reset options ``ArmEnv`` knows."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.control.ik import IKConfig
from osg_control.environment.options import Bounds, check_fields
from osg_control.errors import EnvOptionError
from osg_control.perception.spec import PerceptionSpec

OBS_DIM = 10
ACTION_BOUNDS = np.array([0.02, 0.02, 0.02, 0.1, 0.1, 0.1, 1.0])
"""Per-step bound of each action component: 2 cm, 0.1 rad, and the gripper's [-1, 1]."""
OBS_LOW = np.array([-2.0, -2.0, -2.0, -1.0, -1.0, -1.0, -1.0, -1.0, 0.0, -0.01])
OBS_HIGH = np.array([2.0, 2.0, 2.0, 1.0, 1.0, 1.0, 1.0, 1.0, 70.0, 0.1])
"""Observation bounds: TCP position within 2 m of the base (reach 0.86 m, plus noise), a
unit quaternion, the gripper command, its force (a 70 N gripper's force range) and the
finger distance (0 to 8 cm, with slack for contact penetration); an env's own bounds take
its robot's gripper force and opening (``observation_bounds``)."""
WIDTH_SLACK = 0.02
"""Slack [m] on the finger distance's bound beyond the gripper's opening."""
SIMULATED_PERCEPTIONS = ("paper", "robot", "sim")
"""The perceptions an ``ArmEnv`` simulates (``env`` is an outside env's own observation)."""
RESET_OPTIONS = ("node", "position", "radius", "angle", "gripper", "facts", "world", "holding")
"""The options ``ArmEnv.reset`` knows; any other name is refused."""


@dataclass(frozen=True)
class EnvConfig:
    """Options of ``KitchenEnv``.

    Attributes:
        perception: what the robot perceives and with what noise (``perception.spec``;
            default: the paper's protocol without noise, i.e. the exact state).
        max_steps: episode step budget (truncation); a skill's own budget wins if set;
            None: no truncation (task execution, where the executor bounds each skill).
        ik: the differential-IK controller's configuration.
        start_radius: default random-start radius around the start pose [m].
        start_angle: default random-start angle per axis [rad].
        limit_joint_speed: keep the simulated joint speeds within the URDF velocity limits
            on every physics substep (``control.servo``: the servo's clamped target and the
            drive's speed saturation); off only to compare with the unlimited servo, which
            peaks at 2.7x the limits.

    Raises:
        EnvOptionError: a field of the wrong type or outside its range (``BOUNDS``), named.
    """

    perception: PerceptionSpec = field(default_factory=PerceptionSpec)
    max_steps: int | None = 200
    ik: IKConfig = field(default_factory=IKConfig)
    start_radius: float = 0.0
    start_angle: float = 0.0
    limit_joint_speed: bool = True

    BOUNDS: ClassVar[dict[str, Bounds]] = {
        "max_steps": Bounds(low=1, integer=True, optional=True),
        "start_radius": Bounds(),
        "start_angle": Bounds(),
    }
    """The range of each numeric field."""

    def __post_init__(self) -> None:
        check_fields(self, self.BOUNDS)
        if not isinstance(self.limit_joint_speed, bool):
            raise EnvOptionError(
                f"EnvConfig.limit_joint_speed must be a bool, got {self.limit_joint_speed!r}"
            )
        if not isinstance(self.perception, PerceptionSpec):
            raise EnvOptionError(
                f"EnvConfig.perception must be a PerceptionSpec, got {self.perception!r}"
            )
        if not isinstance(self.ik, IKConfig):
            raise EnvOptionError(f"EnvConfig.ik must be an IKConfig, got {self.ik!r}")


def observation_bounds(robot: RobotDescription) -> tuple[np.ndarray, np.ndarray]:
    """``OBS_LOW``, ``OBS_HIGH`` with the robot's grip force and finger opening."""
    high = OBS_HIGH.copy()
    high[8] = robot.gripper.force
    high[9] = robot.gripper.max_opening + WIDTH_SLACK
    return OBS_LOW.copy(), high


def as_slice(indices: list[int]) -> slice | np.ndarray:
    """Model indices as a slice when consecutive (numpy then indexes without copying; the
    physics loop reads the arm's joints on every substep), else as an index array."""
    first = indices[0]
    if indices == list(range(first, first + len(indices))):
        return slice(first, first + len(indices))
    return np.array(indices)
