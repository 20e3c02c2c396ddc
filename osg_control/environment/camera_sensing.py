"""The ``camera`` perception's object poses: fixed cameras, a colour mask and depth.

A scene declares its cameras and what they look for (``CameraPerception``); the env's
``CameraSensing`` renders them at the perception's rate (``PerceptionSpec.camera_every``
control steps) and at every decision point (a reset, the end of a joint reset, an explicit
``sense``, and the step after a held target's grasp is lost: where did it go?), and
locates each target (``perception.colour_pose``): the camera that last saw a target
first, the others only while a target is still unlocated. Between renders, and while a
target is out of sight (its mask too small: occluded, in the hand, blank images),
its last estimate is kept with its age; a target the robot perceived itself holding moves
with the perceived TCP, at the offset it had from the TCP when last seen or when the
grasp closed (the hand carries it), as a robot predicts what its gripper holds. A target
never seen has no estimate: its world fields are NaN, so none of its facts hold.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from functools import partial
from typing import Any

import mujoco
import numpy as np

from osg_control.perception.camera import CameraRig, camera_setups
from osg_control.perception.colour_pose import (
    ColourTarget,
    Sighting,
    best_sighting,
    colour_mask,
    locate,
    visible,
)
from osg_control.perception.spec import PerceptionSpec

POSE_FIELDS = 7
"""A target's world fields: its centre (x, y, z) and its quaternion (w, x, y, z)."""


@dataclass(frozen=True)
class CameraPerception:
    """A scene's cameras and the targets they locate.

    Attributes:
        cameras: the model cameras' names.
        targets: what the colour mask looks for.
        fields: target name -> its 7 world fields (centre x, y, z, quaternion w, x, y, z).
    """

    cameras: tuple[str, ...]
    targets: tuple[ColourTarget, ...]
    fields: Mapping[str, tuple[str, ...]]

    def __post_init__(self) -> None:
        for target in self.targets:
            if len(self.fields.get(target.name, ())) != POSE_FIELDS:
                raise ValueError(
                    f"camera target {target.name!r}: name its {POSE_FIELDS} pose fields "
                    "(x, y, z, qw, qx, qy, qz)"
                )


class CameraSensing:
    """Renders a scene's cameras at a rate and keeps each target's estimate and age.

    Args:
        model: the compiled scene (its cameras named by ``declared``).
        declared: the scene's cameras and targets.
        spec: the ``camera`` perception (rate and image size).
        world_fields: the env's world fields, in vector order.
        control_hz: the arm's control rate [Hz] (``camera_every`` steps between renders).

    Raises:
        UsageError: a camera the scene lacks, or an image over its offscreen buffer.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        declared: CameraPerception,
        spec: PerceptionSpec,
        world_fields: Iterable[str],
        control_hz: float,
    ) -> None:
        scratch = mujoco.MjData(model)
        mujoco.mj_kinematics(model, scratch)
        mujoco.mj_camlight(model, scratch)  # the cameras' poses
        setups = camera_setups(
            model, scratch, declared.cameras, spec.image_width, spec.image_height
        )
        self.rig = CameraRig(model, setups)
        self.targets = declared.targets
        index = {name: i for i, name in enumerate(world_fields)}
        self._fields = {
            t.name: np.array([index[f] for f in declared.fields[t.name]]) for t in self.targets
        }
        self.period = spec.camera_every / control_hz
        """Simulated seconds between two renders outside decision points."""
        self.renders = 0
        """Renders (of every camera) since the env was made."""
        self.seconds = 0.0
        """Wall time spent rendering and estimating since the env was made [s]."""
        self.reset()

    def reset(self) -> None:
        """Forget every estimate (a new episode)."""
        self._last_render: float | None = None
        self._estimate: dict[str, np.ndarray] = {}
        self._seen_at: dict[str, float] = {}
        self._in_hand: dict[str, np.ndarray] = {}
        self._pixels: dict[str, int] = {}
        self._held_before: set[str] = set()
        self._seen_by = [-math.inf] * len(self.rig.setups)
        """When each camera last saw a target (the first to render next time)."""

    def read(
        self,
        data: mujoco.MjData,
        tcp: np.ndarray,
        world: np.ndarray,
        held: set[str],
        decision: bool,
    ) -> np.ndarray:
        """``world`` with each target's pose fields from the cameras (NaN: never seen).

        Args:
            data: the simulator's state to render.
            tcp: the perceived TCP position [m] (carries a held target).
            world: the perceived world vector to fill in.
            held: the targets the robot perceived itself holding at its last percept.
            decision: a decision point: render whatever the rate.
        """
        now = float(data.time)
        seen: set[str] = set()
        released = bool(self._held_before - held)  # a grasp just lost: look where it fell
        self._held_before = set(held)
        due = self._last_render is None or now - self._last_render >= self.period - 1e-9
        if decision or released or due:
            seen = self._look(data, now)
        out = np.array(world, dtype=float)
        for target in self.targets:
            name = target.name
            estimate = self._estimate.get(name)
            if estimate is not None and name not in seen and name in held:
                estimate[:3] = tcp + self._in_hand[name]
            elif estimate is not None:  # resting, or seen: where it sits relative to the TCP
                self._in_hand[name] = estimate[:3] - tcp
            out[self._fields[name]] = self._estimate.get(name, np.full(POSE_FIELDS, np.nan))
        return out

    def _look(self, data: mujoco.MjData, now: float) -> set[str]:
        """Render the cameras and locate the targets; return the targets seen.

        The cameras are rendered in order of the latest to have seen a target, and
        rendering stops once every target is located (one camera usually sees them all:
        the others' renders are saved)."""
        started = time.perf_counter()
        sightings: dict[str, list[Sighting]] = {t.name: [] for t in self.targets}
        for index in sorted(range(len(self.rig.setups)), key=lambda i: -self._seen_by[i]):
            masks: list[np.ndarray] = []
            _rgb, depth = self.rig.render(data, index, partial(self._masks_into, masks))
            if depth is None:
                continue
            for mask, target in zip(masks, self.targets, strict=True):
                sighting = locate(self.rig.setups[index], mask, depth, target)
                if sighting is not None:
                    sightings[target.name].append(sighting)
                    self._seen_by[index] = now
            if all(sightings.values()):
                break
        seen = set()
        for target in self.targets:
            sighting = best_sighting(list(sightings[target.name]))
            self._pixels[target.name] = 0 if sighting is None else sighting.pixels
            if sighting is None:
                continue
            half = sighting.yaw / 2
            pose = np.concatenate([sighting.position, [math.cos(half), 0.0, 0.0, math.sin(half)]])
            self._estimate[target.name] = pose
            self._seen_at[target.name] = now
            seen.add(target.name)
        self._last_render = now
        self.renders += 1
        self.seconds += time.perf_counter() - started
        return seen

    def _masks_into(self, masks: list[np.ndarray], rgb: np.ndarray) -> bool:
        """Append each target's mask of ``rgb`` to ``masks``; whether any target shows."""
        masks.extend(colour_mask(rgb, target) for target in self.targets)
        return any(visible(m, t) for m, t in zip(masks, self.targets, strict=True))

    def ages(self, now: float) -> dict[str, float | None]:
        """Seconds since each target was last seen (None: never)."""
        return {
            t.name: (None if t.name not in self._seen_at else round(now - self._seen_at[t.name], 4))
            for t in self.targets
        }

    def report(self, now: float) -> dict[str, Any]:
        """The step info's ``camera`` entry: each target's age [s] and last mask size."""
        return {"age_s": self.ages(now), "pixels": dict(self._pixels)}

    def close(self) -> None:
        """Free the renderer."""
        self.rig.close()
