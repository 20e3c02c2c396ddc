"""``ObjectTracker``: where the domain's objects are, estimated from the perceived poses.

The pose estimator's readings are noisy (``robot`` perception: 1 cm per reading); a resting
object does not move, so its estimate is the running mean of its readings. A reading more
than ``JUMP`` from the mean means the object was moved (a grasp that nudged it, a push): the
mean restarts there. While the robot holds the object (its ``held_fact`` perceived) the
estimate is frozen where it was picked up: the frame of a skill that carries the object
(e.g. lifting it) stays where the object lay. An object first seen already held (a start
with it in the hand) has two estimates of where the hand took it: its own first reading,
and the TCP of that reading plus the running mean of its readings relative to the TCP
(which averages the object's noise down but keeps that one TCP reading's). The tracker
weighs them by the perception's declared noise (``reading_weight``): exact objects and a
noisy TCP (the paper's protocol) take the object's reading, an encoder-exact TCP and a
noisy pose estimator (``robot``) the TCP's estimate.
"""

from __future__ import annotations

import numpy as np

from osg_control.domain.base import Domain
from osg_control.domain.frames import offsets_of
from osg_control.perception.percept import Percept
from osg_control.perception.spec import PerceptionSpec

JUMP = 0.04
"""A reading this far [m] from the estimate restarts it: 4 sigma of the robot perception's
1 cm object noise (a false restart about once in 3000 readings), less than a nudge."""


def reading_weight(tcp_noise: float, object_noise: float) -> float:
    """The weight of an object's own first reading, against the TCP's estimate, for an
    object first seen held: inverse-variance, ``tcp² / (tcp² + object²)`` with the noise
    levels [m] per axis. 1 with exact object readings, 0 with an exact TCP and noisy
    objects; 1 with both exact (the two estimates agree)."""
    tcp, obj = float(tcp_noise) ** 2, float(object_noise) ** 2
    return 1.0 if tcp + obj == 0.0 else tcp / (tcp + obj)


class ObjectTracker:
    """Running estimates of each object's displacement from its nominal place.

    Args:
        domain: whose objects to track.
        jump: a reading this far [m] from the estimate restarts it.
        perception: the perception the readings come from: its declared TCP and object
            noise weigh the two estimates of an object first seen held (default: exact
            readings).
    """

    def __init__(
        self, domain: Domain, jump: float = JUMP, perception: PerceptionSpec | None = None
    ) -> None:
        self.domain = domain
        self.jump = jump
        spec = PerceptionSpec() if perception is None else perception
        self.reading_weight = reading_weight(spec.tcp_position_noise, spec.object_noise)
        """The weight of a held-first object's own reading (``reading_weight``)."""
        self._mean: dict[str, np.ndarray] = {}
        self._count: dict[str, int] = {}
        self._in_hand: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, int]] = {}
        """Objects first seen already held: their first reading, the TCP then, and the
        running mean (and count) of the object's reading relative to the TCP."""

    def reset(self) -> None:
        """Forget every estimate (a new episode)."""
        self._mean.clear()
        self._count.clear()
        self._in_hand.clear()

    def update(self, percept: Percept) -> None:
        """Fold in one percept's object readings."""
        readings = offsets_of(self.domain.objects, self.domain.world_fields, percept.world)
        for frame in self.domain.objects:
            name, reading = frame.name, readings[frame.name]
            if not np.isfinite(reading).all():
                continue  # not seen (a camera that never saw it): no reading to fold in
            held = frame.held_fact in percept.facts
            if held and (name not in self._mean or name in self._in_hand):
                self._fold_in_hand(name, reading, percept.position)
                continue
            if held:
                continue  # held: frozen where it was picked up
            self._in_hand.pop(name, None)
            mean = self._mean.get(name)
            if mean is None or float(np.linalg.norm(reading - mean)) > self.jump:
                self._mean[name], self._count[name] = reading, 1
            else:
                self._count[name] += 1
                self._mean[name] = mean + (reading - mean) / self._count[name]

    def _fold_in_hand(self, name: str, reading: np.ndarray, tcp: np.ndarray) -> None:
        """An object first seen held: where it was picked up is its first reading weighed
        against the TCP then plus the object's mean place in the hand (the hand carries
        it, so its reading relative to the TCP averages even while it moves)."""
        relative = reading - np.array([tcp[0], tcp[1], 0.0])
        if name not in self._in_hand:
            start = np.array([tcp[0], tcp[1], 0.0])
            self._in_hand[name] = (reading.copy(), start, relative, 1)
        else:
            first, start, mean, count = self._in_hand[name]
            count += 1
            self._in_hand[name] = (first, start, mean + (relative - mean) / count, count)
        first, start, mean, count = self._in_hand[name]
        weight = self.reading_weight
        self._mean[name] = weight * first + (1.0 - weight) * (start + mean)
        self._count[name] = count

    def offsets(self) -> dict[str, np.ndarray]:
        """Each object's estimated displacement (copies)."""
        return {name: mean.copy() for name, mean in self._mean.items()}
