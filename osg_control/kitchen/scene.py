"""The kitchen scene: ``robots/kitchen.xml`` furniture with the URDF Panda attached at the origin.

Also finds the world's movable parts in the compiled model and reads their state
(``world.WorldState``) for skill effects and evaluation. Policies never see it.
"""

from __future__ import annotations

import os
from pathlib import Path

import mujoco
import numpy as np

from osg_control.control.scene_model import home_keyed_model, with_panda
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
    """Compose the kitchen with the Panda mounted at the world origin."""
    return with_panda(mujoco.MjSpec.from_file(str(kitchen_xml_path())))


def build_kitchen_model() -> mujoco.MjModel:
    """Compile the kitchen with a full-state ``HOME_KEY`` keyframe (arm home, door shut)."""
    return home_keyed_model(kitchen_spec())


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
