"""The env's options and fixed facts: ``EnvConfig`` and the reset options ``ArmEnv`` knows
(the state and action sizes and bounds are ``domain.spaces``'s, the simulated perceptions
``perception.spec.SIMULATED_PERCEPTIONS``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from osg_control.control.ik import IKConfig
from osg_control.environment.options import Bounds, check_fields
from osg_control.errors import EnvOptionError
from osg_control.perception.spec import PerceptionSpec

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


def as_slice(indices: list[int]) -> slice | np.ndarray:
    """Model indices as a slice when consecutive (numpy then indexes without copying; the
    physics loop reads the arm's joints on every substep), else as an index array."""
    first = indices[0]
    if indices == list(range(first, first + len(indices))):
        return slice(first, first + len(indices))
    return np.array(indices)
