"""The kitchen's cameras for the ``camera`` perception: two fixed cameras and the cubes.

``counter_cam`` faces the arm across the cubes' placement region (it sees a cube resting
and, from the side, held in the hand); ``cabinet_cam`` looks down into the cabinet through
its opening (a placed cube). Both are ``<camera>`` elements of ``robots/kitchen.xml``. Each
cube is the scene's only thing of its colour (``cubes.COLOURS``: red, blue, yellow): its
mask is the hues within ``HUE_MARGIN`` of its own; the brown door (hue about 13 of 179),
the beige counter (unsaturated) and the grey metal stay out.
"""

from __future__ import annotations

from functools import cache

import cv2
import numpy as np

from osg_control.environment.camera_sensing import POSE_FIELDS, CameraPerception
from osg_control.kitchen.cubes import COLOURS
from osg_control.kitchen.objects import cube_prefix
from osg_control.kitchen.world import CUBE_FIELDS, CUBE_HALF_SIZE
from osg_control.perception.colour_pose import ColourTarget

HUE_MARGIN = 6
"""A cube's mask takes the hues within this many OpenCV hue units (0-179) of its colour's."""
HUE_STEPS = 180
"""OpenCV's hue circle of 8-bit images."""


def hue_ranges(rgba: tuple[float, float, float, float]) -> tuple[tuple[int, int], ...]:
    """The OpenCV hue intervals within ``HUE_MARGIN`` of a colour's hue (two where they
    wrap past 0, as red's do)."""
    pixel = np.array([[[round(255 * c) for c in rgba[:3]]]], dtype=np.uint8)
    hue = int(cv2.cvtColor(pixel, cv2.COLOR_RGB2HSV)[0, 0, 0])
    low, high = hue - HUE_MARGIN, hue + HUE_MARGIN
    if low < 0:
        return ((0, high), (HUE_STEPS + low, HUE_STEPS - 1))
    if high >= HUE_STEPS:
        return ((0, high - HUE_STEPS), (low, HUE_STEPS - 1))
    return ((low, high),)


def cube_target(k: int) -> ColourTarget:
    """Cube k's colour target: its colour's hues, its size."""
    return ColourTarget(
        name=cube_prefix(k),
        hue_ranges=hue_ranges(COLOURS[k - 1]),
        min_saturation=120,
        min_value=60,
        half_height=CUBE_HALF_SIZE,
    )


@cache
def kitchen_cameras(cubes: int = 1) -> CameraPerception:
    """What the kitchen's camera perception renders and looks for with ``cubes`` cubes."""
    pose = CUBE_FIELDS[:POSE_FIELDS]  # x, y, z, qw, qx, qy, qz
    return CameraPerception(
        cameras=("counter_cam", "cabinet_cam"),
        targets=tuple(cube_target(k) for k in range(1, cubes + 1)),
        fields={
            cube_prefix(k): tuple(f"{cube_prefix(k)}_{f}" for f in pose)
            for k in range(1, cubes + 1)
        },
    )
