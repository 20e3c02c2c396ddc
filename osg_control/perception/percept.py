"""``Percept``: one reading of everything a robot measures, and the facts read from it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class Percept:
    """What the robot perceives at one control step.

    Attributes:
        state: the 10-D policy state (TCP position and orientation, gripper command, grip
            force, finger width), from the perceived joints or the paper's noisy TCP.
        joints: the perceived arm joint positions [rad].
        world: the perceived world vector (the domain's ``world_fields``): object poses
            from the pose estimator, detector fields from the other percepts.
        facts: the domain's facts on ``world`` (its detectors).
    """

    state: np.ndarray
    joints: np.ndarray
    world: np.ndarray
    facts: frozenset[str]

    def __eq__(self, other: object) -> bool:
        """Equal readings (arrays compared element-wise): Gymnasium's determinism check
        compares step infos."""
        if not isinstance(other, Percept):
            return NotImplemented
        return (
            self.facts == other.facts
            and np.array_equal(self.state, other.state)
            and np.array_equal(self.joints, other.joints)
            and np.array_equal(self.world, other.world)
        )

    __hash__ = None  # type: ignore[assignment]

    @property
    def position(self) -> np.ndarray:
        """The perceived TCP position [m]."""
        return self.state[:3]
