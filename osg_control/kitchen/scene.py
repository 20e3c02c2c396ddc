"""The kitchen scene: ``robots/kitchen.xml`` furniture with a robot at its mount.

Also finds the world's movable parts in the compiled model and reads their state
(``world.WorldState``) for skill effects and evaluation. Policies never see it.
"""

from __future__ import annotations

import os
from pathlib import Path

import mujoco

from osg_control.control.description import ORIGIN, Placement, RobotDescription, mounted
from osg_control.control.scene_model import home_keyed_model, with_robot
from osg_control.errors import ModelNotFoundError
from osg_control.kitchen.world import WorldState
from osg_control.paths import PACKAGE_DIR
from osg_control.robots.registry import get_robot

ROBOT_MOUNTS: dict[str, Placement] = {"ur5": ((0.10, 0.15, 0.0), (1.0, 0.0, 0.0, 0.0))}
"""Where a robot's base stands in the kitchen (the others stand at the origin, the Panda's
place). The UR5 stands on the counter top, 10 cm ahead of and 15 cm to the cabinet's side of
the origin, not rotated: at the origin ``release-handle``'s lift point (0.42 0.54 0.50, TCP
down) is out of its reach (3 cm short, the elbow straight); here every node and skill path
is reached clear of the furniture (``tools/ur5_kitchen_reach.py``)."""


def kitchen_robot(robot: str | RobotDescription) -> RobotDescription:
    """A registered robot by name at its kitchen mount (``ROBOT_MOUNTS``); a description
    as given (already mounted, or deliberately elsewhere)."""
    if isinstance(robot, RobotDescription):
        return robot
    return mounted(get_robot(robot), ROBOT_MOUNTS.get(robot, ORIGIN))


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


def kitchen_spec(robot: RobotDescription) -> mujoco.MjSpec:
    """Compose the kitchen with ``robot`` (its base at ``robot.mount``)."""
    return with_robot(mujoco.MjSpec.from_file(str(kitchen_xml_path())), robot)


def build_kitchen_model(robot: RobotDescription) -> mujoco.MjModel:
    """Compile the kitchen with a full-state ``HOME_KEY`` keyframe (arm home, door shut)."""
    return home_keyed_model(kitchen_spec(robot), robot)


class SceneIndex:
    """Ids of the named parts of a compiled kitchen model (with ``robot``), looked up once."""

    def __init__(self, model: mujoco.MjModel, robot: RobotDescription) -> None:
        self.door_qpos = model.joint("door_slide").qposadr[0]
        self.valve_qpos = model.joint("valve_hinge").qposadr[0]
        self.cube_qpos = model.joint("cube_free").qposadr[0]
        self.cube_geom = model.geom("cube").id
        self.handle_geom = model.geom("handle").id
        self.left_finger, self.right_finger = (model.body(b).id for b in robot.gripper.bodies)

    def _grasped(self, model: mujoco.MjModel, data: mujoco.MjData) -> tuple[bool, bool]:
        """Whether the cube, and the handle, touch both fingers: one vectorised pass over
        the contacts (iterating ``data.contact`` in Python costs about 10 us per contact)."""
        pairs = data.contact.geom  # (ncon, 2)
        if not len(pairs):
            return False, False
        bodies = model.geom_bodyid[pairs]  # (ncon, 2)
        left = (bodies == self.left_finger)[:, ::-1]  # the other side of each pair
        right = (bodies == self.right_finger)[:, ::-1]
        grasped = []
        for geom in (self.cube_geom, self.handle_geom):
            side = pairs == geom
            grasped.append(bool((side & left).any() and (side & right).any()))
        return grasped[0], grasped[1]

    def read(self, model: mujoco.MjModel, data: mujoco.MjData) -> WorldState:
        """Read the world state from the simulator (copies, never aliases ``data``)."""
        cube = data.qpos[self.cube_qpos : self.cube_qpos + 7].tolist()
        cube_grasped, handle_grasped = self._grasped(model, data)
        return WorldState(
            door_opening=float(data.qpos[self.door_qpos]),
            valve_angle=float(data.qpos[self.valve_qpos]),
            cube_pos=(cube[0], cube[1], cube[2]),
            cube_quat=(cube[3], cube[4], cube[5], cube[6]),
            cube_grasped=cube_grasped,
            handle_grasped=handle_grasped,
        )
