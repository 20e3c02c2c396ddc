"""Simulated sensors: noise on the simulator's readings by sensor kind.

A domain's env declares, per world field, which sensor reads it (``WorldSensor``): an
object position (the pose estimator's position noise), a fixture's position (an object
that moves only between episodes; the same noise drawn from a stream of its own, so adding
one changes no other reading), an angle or an orientation quaternion (its orientation
noise), or a detector (``DETECTED``: recomputed by the domain
from the other percepts, e.g. a grasp from the finger width and the object's pose).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import mujoco
import numpy as np

from osg_control.perception.spec import PerceptionSpec

POSITION = "position"
FIXTURE = "fixture"
ANGLE = "angle"
QUATERNION = "quaternion"
DETECTED = "detected"
SENSOR_KINDS = (POSITION, FIXTURE, ANGLE, QUATERNION, DETECTED)
"""What can read a world field."""


def check_world_sensors(
    sensors: Mapping[str, str], world_fields: Sequence[str], owner: str
) -> None:
    """Every world field has exactly one known sensor kind, in field order.

    Raises:
        ValueError: naming the owner and the fields that differ.
    """
    if tuple(sensors) != tuple(world_fields):
        raise ValueError(
            f"{owner}: world sensors {list(sensors)} do not match world fields {list(world_fields)}"
        )
    unknown = {name: kind for name, kind in sensors.items() if kind not in SENSOR_KINDS}
    if unknown:
        raise ValueError(f"{owner}: unknown sensor kinds {unknown}; known: {SENSOR_KINDS}")


def sensor_slices(sensors: Mapping[str, str]) -> dict[str, np.ndarray]:
    """Field indices per sensor kind (quaternions as runs of four)."""
    kinds = list(sensors.values())
    return {kind: np.array([i for i, k in enumerate(kinds) if k == kind]) for kind in SENSOR_KINDS}


def noisy_world(
    spec: PerceptionSpec,
    rng: np.random.Generator,
    world: np.ndarray,
    slices: Mapping[str, np.ndarray],
    fixture_rng: np.random.Generator | None = None,
) -> np.ndarray:
    """The pose estimator's reading of a world vector (detector fields left as they are:
    the domain recomputes them). Draws nothing when the objects are perceived exactly.
    ``FIXTURE`` fields draw from ``fixture_rng`` (default ``rng``), so a caller that keeps
    one apart leaves ``rng``'s draws as they were without them."""
    seen = np.array(world, dtype=float)
    if spec.object_noise > 0 and slices[POSITION].size:
        seen[slices[POSITION]] += rng.normal(0.0, spec.object_noise, slices[POSITION].size)
    if spec.object_noise > 0 and slices[FIXTURE].size:
        fixtures = rng if fixture_rng is None else fixture_rng
        seen[slices[FIXTURE]] += fixtures.normal(0.0, spec.object_noise, slices[FIXTURE].size)
    if spec.object_angle_noise > 0:
        if slices[ANGLE].size:
            seen[slices[ANGLE]] += rng.normal(0.0, spec.object_angle_noise, slices[ANGLE].size)
        quats = slices[QUATERNION]
        for start in range(0, quats.size, 4):
            index = quats[start : start + 4]
            seen[index] = rotated_quat(seen[index], rng.normal(0.0, spec.object_angle_noise, 3))
    return seen


def rotated_quat(quat: np.ndarray, rotation_vector: np.ndarray) -> np.ndarray:
    """``quat`` (w, x, y, z) turned by a small rotation vector [rad] (MuJoCo's
    ``mju_quatIntegrate``; the noise is isotropic, so the frame does not matter)."""
    turned = np.array(quat, dtype=float)
    mujoco.mju_quatIntegrate(turned, np.asarray(rotation_vector, dtype=float), 1.0)
    return turned
