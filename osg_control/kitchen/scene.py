"""The kitchen scene: ``robots/kitchen.xml`` furniture with the URDF Panda attached at the origin.

Also finds the world's movable parts in the compiled model and reads their state
(``world.WorldState``) for skill effects and evaluation. Policies never see it.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import mujoco
import numpy as np

from osg_control.control.robot import (
    ARM_JOINTS,
    FINGER_JOINTS,
    FINGER_OPEN,
    HOME_KEY,
    HOME_Q,
    panda_spec,
)
from osg_control.errors import ModelNotFoundError
from osg_control.kitchen.world import WorldState
from osg_control.paths import PACKAGE_DIR


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
    spec.add_key(name=HOME_KEY, qpos=qpos, ctrl=ctrl)
    return _compile(spec)


def _compile(spec: mujoco.MjSpec) -> mujoco.MjModel:
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")
        return spec.compile()


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
