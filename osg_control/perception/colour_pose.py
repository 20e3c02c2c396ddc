"""Locating a coloured box from an RGB + depth image: an HSV colour mask and the depth.

The method (``locate``):

1. the pixels whose HSV colour (OpenCV's ``cvtColor`` and ``inRange``: hue 0-179,
   saturation and value 0-255) lies in the target's ranges form its mask;
2. fewer than ``min_pixels`` of them: the target is not seen (occluded, out of view, a
   blank image): no estimate;
3. the masked pixels are back-projected by their depth into world points;
4. the top face is the points within ``top_band`` of the 95th percentile of their height
   (a robust top: an anti-aliased edge pixel does not move it), side faces dropped;
5. the centre is the top face's centroid lowered by ``half_height``; when those points
   are only a rim (narrower across than half the box: the top hidden, e.g. under the
   hand), it is moved half the box away from the camera across the rim; the yaw is the
   angle of OpenCV's ``minAreaRect`` around the top face's points, modulo a quarter turn
   (a square face).

The object is taken upright (its top face horizontal), as a box resting or held by a
top-down grasp is. No segmentation image or simulator pose is read.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from osg_control.perception.camera import CameraSetup, back_project

TOP_QUANTILE = 95.0
"""The percentile of the masked points' heights taken as the top face's height."""


@dataclass(frozen=True)
class ColourTarget:
    """A box-shaped object a colour mask finds.

    Attributes:
        name: the object's name (the domain's ``ObjectFrame``).
        hue_ranges: OpenCV hue intervals (0-179) of its colour, inclusive (red wraps: two).
        min_saturation, min_value: the least saturation and value (0-255) of its pixels.
        half_height: from its top face down to its centre [m].
        min_pixels: fewer masked pixels than this: not seen.
        top_band: how far below the top [m] a point still counts on the top face.
    """

    name: str
    hue_ranges: tuple[tuple[int, int], ...]
    min_saturation: int
    min_value: int
    half_height: float
    min_pixels: int = 20
    top_band: float = 0.004


@dataclass(frozen=True)
class Sighting:
    """Where one camera saw a target.

    Attributes:
        position: the estimated centre [m], world frame.
        yaw: the top face's angle about the vertical [rad], in [0, pi/2).
        pixels: how many pixels its mask had.
        camera: the camera's name.
    """

    position: np.ndarray
    yaw: float
    pixels: int
    camera: str


def colour_mask(rgb: np.ndarray, target: ColourTarget) -> np.ndarray:
    """The target's mask (uint8, 255 where its colour is) of an RGB image."""
    hsv = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2HSV)
    mask = np.zeros(hsv.shape[:2], dtype=np.uint8)
    for low, high in target.hue_ranges:
        lower = np.array([low, target.min_saturation, target.min_value], dtype=np.uint8)
        upper = np.array([high, 255, 255], dtype=np.uint8)
        mask |= cv2.inRange(hsv, lower, upper)
    return mask


def locate(
    setup: CameraSetup, mask: np.ndarray, depth: np.ndarray, target: ColourTarget
) -> Sighting | None:
    """The target's pose from one camera's mask (``colour_mask``) and depth image (see the
    module docstring), or None when the mask has fewer than ``min_pixels`` pixels."""
    rows, cols = np.nonzero(mask)
    if rows.size < target.min_pixels:
        return None
    points = back_project(setup, rows, cols, depth[rows, cols].astype(float))
    top_z = float(np.percentile(points[:, 2], TOP_QUANTILE))
    top = points[np.abs(points[:, 2] - top_z) <= target.top_band]
    if len(top) < 3:
        return None
    centre = top.mean(axis=0)
    centre[2] = top_z - target.half_height
    centre[:2] += _edge_shift(top[:, :2], centre[:2] - setup.position[:2], target.half_height)
    (_, _), (_, _), angle = cv2.minAreaRect((top[:, :2] * 1000.0).astype(np.float32))
    yaw = math.radians(angle) % (math.pi / 2)
    return Sighting(centre, yaw, int(rows.size), setup.name)


def _edge_shift(points: np.ndarray, away: np.ndarray, half: float) -> np.ndarray:
    """The shift [m] from the centroid of the top's visible points to the box's centre:
    zero for a top face seen whole; half the box away from the camera (``away``: the
    horizontal direction from it) when the points are only an edge, narrower than half the
    box across (the top hidden, e.g. under the hand: the highest red is a side's rim)."""
    if len(points) < 3:
        return np.zeros(2)
    _values, axes = np.linalg.eigh(np.cov(points.T))
    across = axes[:, 0]  # the direction of least spread
    projected = points @ across
    if float(projected.max() - projected.min()) >= half:
        return np.zeros(2)
    return across * half * (1.0 if float(across @ away) >= 0 else -1.0)


def visible(mask: np.ndarray, target: ColourTarget) -> bool:
    """Whether a mask has enough pixels for ``locate``."""
    return cv2.countNonZero(mask) >= target.min_pixels


def best_sighting(sightings: list[Sighting]) -> Sighting | None:
    """The sighting with the most pixels (the camera that sees the target best)."""
    return max(sightings, key=lambda s: s.pixels) if sightings else None
