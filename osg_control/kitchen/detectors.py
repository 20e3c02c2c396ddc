"""The kitchen's perception: which sensor reads each world field, and the grasp detectors.

A robot has no contact oracle: it believes it holds a cube when its gripper is commanded
shut, the finger width reads the cube's width and the perceived cube lies between the
fingers (of several cubes, the one nearest the TCP); the handle likewise with the fin's
width and the handle's perceived place (the ``handle`` node moved with the door's perceived
travel, ``skills.DOOR``).
"""

from __future__ import annotations

import math

import numpy as np

from osg_control.domain.frames import reading_displacement
from osg_control.environment.success import GRIPPER_CLOSED_CMD
from osg_control.kitchen.skills import DOOR, NODES
from osg_control.kitchen.world import (
    CUBE_FIELDS,
    CUBE_HALF_SIZE,
    VALVE_FIELDS,
    WORLD_FIELDS,
    has_valve_fields,
)
from osg_control.perception.sensors import ANGLE, DETECTED, POSITION, QUATERNION

WORLD_SENSORS: dict[str, str] = {
    "door_opening": POSITION,
    "valve_angle": ANGLE,
    "cube_x": POSITION,
    "cube_y": POSITION,
    "cube_z": POSITION,
    "cube_qw": QUATERNION,
    "cube_qx": QUATERNION,
    "cube_qy": QUATERNION,
    "cube_qz": QUATERNION,
    "cube_grasped": DETECTED,
    "handle_grasped": DETECTED,
}
"""World field -> sensor: the pose estimator sees the door's travel, the valve's angle and
the cube's pose; the grasps are detected from the other percepts."""
assert tuple(WORLD_SENSORS) == WORLD_FIELDS

CUBE_GRIP_WIDTH = 2 * (CUBE_HALF_SIZE - 0.0005)
"""Finger width [m] with the fingers shut on the cube."""
HANDLE_GRIP_WIDTH = 0.019
"""Finger width [m] with the fingers shut on the handle's fin."""
WIDTH_BAND = (-0.008, 0.005)
"""How far below and above an object's grip width [m] a shut gripper counts as holding it
(contact penetration squeezes it; a slipping object widens it)."""
GRIP_REACH = 0.06
"""Largest distance [m] from the perceived TCP to the perceived object of a grasp: the
cube's or the handle's noise (1 cm), the TCP's (2 cm under the paper's protocol), and the
grasp's offset from the object's centre."""
_FIELD = {name: i for i, name in enumerate(WORLD_FIELDS)}
_CUBE_POSITION = slice(_FIELD["cube_x"], _FIELD["cube_z"] + 1)
assert WORLD_FIELDS[_CUBE_POSITION] == ("cube_x", "cube_y", "cube_z")
_DOOR_FIELD = _FIELD[DOOR.position_fields[0]]
_CUBE_WIDTH = len(CUBE_FIELDS)
"""World fields per cube beyond the first (its position first, its grasp last)."""
_HANDLE_SHUT = np.asarray(NODES["handle"].position, dtype=float)
"""The handle node with the door shut [m]."""


def _grips(state: np.ndarray, width: float, target: np.ndarray) -> bool:
    shut = state[7] == GRIPPER_CLOSED_CMD
    low, high = width + WIDTH_BAND[0], width + WIDTH_BAND[1]
    gap = state[:3] - target
    near = math.sqrt(gap @ gap) <= GRIP_REACH  # np.linalg.norm's own formula, without its checks
    return bool(shut and low <= state[9] <= high and near)


def detect_grasps(state: np.ndarray, world: np.ndarray) -> np.ndarray:
    """The perceived world with each cube's grasp and ``handle_grasped`` from the percepts.

    Args:
        state: the perceived 10-D state (TCP, gripper command, force, finger width).
        world: the pose estimator's world vector (``world.world_fields(cubes)``; or one
            stored without the valve's fields, ``world.has_valve_fields``).
    """
    detected = np.array(world, dtype=float)
    handle = _HANDLE_SHUT + reading_displacement(DOOR, (detected[_DOOR_FIELD],))
    detected[_FIELD["handle_grasped"]] = float(_grips(state, HANDLE_GRIP_WIDTH, handle))
    cubes_end = len(detected) - (len(VALVE_FIELDS) if has_valve_fields(len(detected)) else 0)
    if cubes_end == len(WORLD_FIELDS):
        cube = detected[_CUBE_POSITION]
        detected[_FIELD["cube_grasped"]] = float(_grips(state, CUBE_GRIP_WIDTH, cube))
        return detected
    starts = [_CUBE_POSITION.start, *range(len(WORLD_FIELDS), cubes_end, _CUBE_WIDTH)]
    grasps = [_FIELD["cube_grasped"], *(i + _CUBE_WIDTH - 1 for i in starts[1:])]
    gaps = [float(np.linalg.norm(state[:3] - detected[i : i + 3])) for i in starts]
    nearest = int(np.argmin(gaps))
    for k, (start, grasp) in enumerate(zip(starts, grasps, strict=True)):
        held = k == nearest and _grips(state, CUBE_GRIP_WIDTH, detected[start : start + 3])
        detected[grasp] = float(held)
    return detected
