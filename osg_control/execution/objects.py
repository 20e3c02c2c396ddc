"""``ObjectTracker``: where the domain's objects are, estimated from the perceived poses.

The pose estimator's readings are noisy (``robot`` perception: 1 cm per reading); a resting
object does not move, so its estimate is the running mean of its readings. A reading more
than ``JUMP`` from the mean means the object was moved (a grasp that nudged it, a push): the
mean restarts there. While the robot holds the object (its ``held_fact`` perceived) the
estimate is frozen where it was picked up: the frame of a skill that carries the object
(e.g. lifting it) stays where the object lay.
"""

from __future__ import annotations

import numpy as np

from osg_control.domain.base import Domain
from osg_control.domain.frames import offsets_of
from osg_control.perception.percept import Percept

JUMP = 0.04
"""A reading this far [m] from the estimate restarts it: 4 sigma of the robot perception's
1 cm object noise (a false restart about once in 3000 readings), less than a nudge."""


class ObjectTracker:
    """Running estimates of each object's displacement from its nominal place."""

    def __init__(self, domain: Domain, jump: float = JUMP) -> None:
        self.domain = domain
        self.jump = jump
        self._mean: dict[str, np.ndarray] = {}
        self._count: dict[str, int] = {}

    def reset(self) -> None:
        """Forget every estimate (a new episode)."""
        self._mean.clear()
        self._count.clear()

    def update(self, percept: Percept) -> None:
        """Fold in one percept's object readings."""
        readings = offsets_of(self.domain.objects, self.domain.world_fields, percept.world)
        for frame in self.domain.objects:
            name, reading = frame.name, readings[frame.name]
            if frame.held_fact in percept.facts and name in self._mean:
                continue  # held: frozen where it was picked up
            mean = self._mean.get(name)
            if mean is None or float(np.linalg.norm(reading - mean)) > self.jump:
                self._mean[name], self._count[name] = reading, 1
            else:
                self._count[name] += 1
                self._mean[name] = mean + (reading - mean) / self._count[name]

    def offsets(self) -> dict[str, np.ndarray]:
        """Each object's estimated displacement (copies)."""
        return {name: mean.copy() for name, mean in self._mean.items()}
