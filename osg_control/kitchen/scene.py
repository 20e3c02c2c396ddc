"""The kitchen scene: ``robots/kitchen.xml`` furniture with the URDF Panda attached at the origin.

Also names the world's movable parts and reads their state (door opening, valve angle, cube
pose, whether the cube is held) for skill effects and evaluation. Policies never see it.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from osg_control.control.robot import ARM_JOINTS, FINGER_JOINTS, FINGER_OPEN, HOME_Q, panda_spec
from osg_control.errors import ModelNotFoundError
from osg_control.paths import PACKAGE_DIR

CUBE_HALF_SIZE = 0.0225
"""Half the cube's edge [m]."""
CABINET_INTERIOR_LOW = np.array([0.52, 0.10, 0.10])
CABINET_INTERIOR_HIGH = np.array([0.84, 0.56, 0.70])
"""Axis-aligned bounds of the cabinet's interior [m], world frame."""
DOOR_OPEN_MIN = 0.30
"""Door travel [m] from which the door counts as open (the opening then clears the cube)."""


def kitchen_xml_path() -> Path:
    """Find ``kitchen.xml`` (``$OSG_ROBOTS_DIR`` or the repository's ``robots/``).

    Raises:
        ModelNotFoundError: naming every path searched.
    """
    candidates = []
    if os.environ.get("OSG_ROBOTS_DIR"):
        candidates.append(Path(os.environ["OSG_ROBOTS_DIR"]) / "kitchen.xml")
    candidates.append(PACKAGE_DIR.parent / "robots" / "kitchen.xml")
    for path in candidates:
        if path.is_file():
            return path
    raise ModelNotFoundError(
        "kitchen scene not found. Searched:\n  " + "\n  ".join(map(str, candidates))
    )


def kitchen_spec() -> mujoco.MjSpec:
    """Compose the kitchen with the Panda mounted at the world origin and a ``home`` key."""
    spec = mujoco.MjSpec.from_file(str(kitchen_xml_path()))
    robot = panda_spec(with_fingers=True)
    for key in list(robot.keys):
        robot.delete(key)
    frame = spec.worldbody.add_frame()
    with warnings.catch_warnings():
        # The robot's URDF names are unique in the scene, so no prefix is needed.
        warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")
        spec.attach(robot, frame=frame, prefix="")
    return spec


def build_kitchen_model() -> mujoco.MjModel:
    """Compile the kitchen and add a full-state ``home`` keyframe (arm home, door shut)."""
    spec = kitchen_spec()
    model = _compile(spec)
    data = mujoco.MjData(model)
    qpos = data.qpos.copy()
    ctrl = np.zeros(model.nu)
    for name, value in zip(ARM_JOINTS, HOME_Q, strict=True):
        qpos[model.joint(name).qposadr[0]] = value
        ctrl[model.actuator(name).id] = value
    for name in FINGER_JOINTS:
        qpos[model.joint(name).qposadr[0]] = FINGER_OPEN
    ctrl[model.actuator("gripper").id] = FINGER_OPEN
    spec.add_key(name="home", qpos=qpos, ctrl=ctrl)
    return _compile(spec)


def _compile(spec: mujoco.MjSpec) -> mujoco.MjModel:
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")
        return spec.compile()


@dataclass(frozen=True)
class WorldState:
    """What the simulator knows beyond the robot's 10-D state (never fed to policies).

    Attributes:
        door_opening: door travel along its slide [m] (0 = shut).
        valve_angle: valve knob angle [rad].
        cube_pos: cube centre [m], world = robot base frame.
        cube_quat: cube orientation, ``w, x, y, z``.
        cube_grasped: both fingers touch the cube.
        handle_grasped: both fingers touch the door handle.
    """

    door_opening: float
    valve_angle: float
    cube_pos: tuple[float, float, float]
    cube_quat: tuple[float, float, float, float]
    cube_grasped: bool
    handle_grasped: bool

    @property
    def door_open(self) -> bool:
        """The door has slid far enough to clear the cabinet's opening."""
        return self.door_opening >= DOOR_OPEN_MIN

    @property
    def cube_in_cabinet(self) -> bool:
        """The cube rests in the cabinet: its centre inside the interior box, not grasped."""
        pos = np.asarray(self.cube_pos)
        inside = np.all(pos > CABINET_INTERIOR_LOW) and np.all(pos < CABINET_INTERIOR_HIGH)
        return bool(inside and not self.cube_grasped)

    @property
    def cube_on_counter(self) -> bool:
        """The cube rests on the counter (not lifted, not in the cabinet)."""
        return self.cube_pos[2] < CUBE_HALF_SIZE + 0.01 and not self.cube_in_cabinet

    @property
    def cube_lifted(self) -> bool:
        """The cube is held clear of every surface (5 cm above the counter or more)."""
        return self.cube_grasped and self.cube_pos[2] > CUBE_HALF_SIZE + 0.05

    def as_array(self) -> np.ndarray:
        """Flat float vector (see ``WORLD_FIELDS``) for storage in data sets."""
        return np.array(
            [
                self.door_opening,
                self.valve_angle,
                *self.cube_pos,
                *self.cube_quat,
                float(self.cube_grasped),
                float(self.handle_grasped),
            ]
        )


def world_facts(world: WorldState) -> frozenset[str]:
    """Abstract a world state into the kitchen's PDDL facts (``skills.WORLD_FACTS``).

    Args:
        world: the simulator's world state.

    Returns:
        The facts that hold; hand-empty means neither the cube nor the handle is grasped.
    """
    facts = {"door-open" if world.door_open else "door-closed"}
    named = {
        "cube-in-cabinet": world.cube_in_cabinet,
        "cube-on-counter": world.cube_on_counter,
        "cube-lifted": world.cube_lifted,
        "holding-cube": world.cube_grasped,
        "holding-handle": world.handle_grasped,
        "hand-empty": not (world.cube_grasped or world.handle_grasped),
    }
    return frozenset(facts | {name for name, holds in named.items() if holds})


WORLD_FIELDS: tuple[str, ...] = (
    "door_opening",
    "valve_angle",
    "cube_x",
    "cube_y",
    "cube_z",
    "cube_qw",
    "cube_qx",
    "cube_qy",
    "cube_qz",
    "cube_grasped",
    "handle_grasped",
)


def world_state_from_array(values: np.ndarray) -> WorldState:
    """Inverse of ``WorldState.as_array``."""
    v = np.asarray(values, dtype=float)
    return WorldState(
        door_opening=float(v[0]),
        valve_angle=float(v[1]),
        cube_pos=(float(v[2]), float(v[3]), float(v[4])),
        cube_quat=(float(v[5]), float(v[6]), float(v[7]), float(v[8])),
        cube_grasped=bool(v[9] > 0.5),
        handle_grasped=bool(v[10] > 0.5),
    )


class SceneIndex:
    """Ids of the named parts of a compiled kitchen model, looked up once."""

    def __init__(self, model: mujoco.MjModel) -> None:
        self.door_qpos = model.joint("door_slide").qposadr[0]
        self.valve_qpos = model.joint("valve_hinge").qposadr[0]
        self.cube_qpos = model.joint("cube_free").qposadr[0]
        self.cube_geom = model.geom("cube").id
        self.handle_geom = model.geom("handle").id
        self.left_finger = model.body("panda_leftfinger").id
        self.right_finger = model.body("panda_rightfinger").id

    def _touches_both_fingers(self, model: mujoco.MjModel, data: mujoco.MjData, geom: int) -> bool:
        # Vectorised over the contact arrays: iterating ``data.contact`` in Python costs
        # about 10 us per contact, which dominated the env step's overhead.
        pairs = data.contact.geom  # (ncon, 2)
        others = np.concatenate([pairs[pairs[:, 0] == geom, 1], pairs[pairs[:, 1] == geom, 0]])
        touched = model.geom_bodyid[others]
        return bool(np.any(touched == self.left_finger) and np.any(touched == self.right_finger))

    def read(self, model: mujoco.MjModel, data: mujoco.MjData) -> WorldState:
        """Read the world state from the simulator (copies, never aliases ``data``)."""
        cube = data.qpos[self.cube_qpos : self.cube_qpos + 7]
        return WorldState(
            door_opening=float(data.qpos[self.door_qpos]),
            valve_angle=float(data.qpos[self.valve_qpos]),
            cube_pos=(float(cube[0]), float(cube[1]), float(cube[2])),
            cube_quat=(float(cube[3]), float(cube[4]), float(cube[5]), float(cube[6])),
            cube_grasped=self._touches_both_fingers(model, data, self.cube_geom),
            handle_grasped=self._touches_both_fingers(model, data, self.handle_geom),
        )
