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
from osg_control.kitchen.cubes import COLOURS, REST_PLACES
from osg_control.kitchen.objects import cube_prefix
from osg_control.kitchen.world import CubeState, WorldState
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


def kitchen_spec(robot: RobotDescription, cubes: int = 1) -> mujoco.MjSpec:
    """Compose the kitchen with ``robot`` (its base at ``robot.mount``) and ``cubes`` cubes
    (``add_cubes``; one: the file's scene as it is)."""
    spec = mujoco.MjSpec.from_file(str(kitchen_xml_path()))
    add_cubes(spec, cubes)
    return with_robot(spec, robot)


def add_cubes(spec: mujoco.MjSpec, cubes: int) -> None:
    """Add cubes 2 ... ``cubes`` to the kitchen's spec: copies of its ``cube`` body (size,
    mass, friction) named ``cube2`` ... (body, geom; joint ``cube2_free``), each its own
    colour (``cubes.COLOURS``), resting at ``cubes.REST_PLACES``."""
    first = spec.geom("cube")
    for k in range(2, cubes + 1):
        name = cube_prefix(k)
        x, y = REST_PLACES[k - 1]
        body = spec.worldbody.add_body(name=name, pos=[x, y, first.size[2]])
        body.add_freejoint(name=f"{name}_free")
        body.add_geom(
            name=name,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=first.size,
            mass=first.mass,
            friction=first.friction,
            condim=first.condim,
            rgba=COLOURS[k - 1],
        )


def build_kitchen_model(robot: RobotDescription, cubes: int = 1) -> mujoco.MjModel:
    """Compile the kitchen with a full-state ``HOME_KEY`` keyframe (arm home, door shut)."""
    return home_keyed_model(kitchen_spec(robot, cubes), robot)


class SceneIndex:
    """Ids of the named parts of a compiled kitchen model (with ``robot``), looked up once."""

    def __init__(self, model: mujoco.MjModel, robot: RobotDescription, cubes: int = 1) -> None:
        self.door_qpos = model.joint("door_slide").qposadr[0]
        self.valve_qpos = model.joint("valve_hinge").qposadr[0]
        self.valve_body = model.body("valve").id
        names = [cube_prefix(k) for k in range(1, cubes + 1)]
        self.cube_qposes = [model.joint(f"{name}_free").qposadr[0] for name in names]
        """Each cube's free joint's first qpos address, cube 1 first."""
        self.cube_geoms = [model.geom(name).id for name in names]
        """Each cube's geom, cube 1 first."""
        self.cube_qpos, self.cube_geom = self.cube_qposes[0], self.cube_geoms[0]
        self.handle_geom = model.geom("handle").id
        self.left_finger, self.right_finger = (model.body(b).id for b in robot.gripper.bodies)

    def _grasped(self, model: mujoco.MjModel, data: mujoco.MjData) -> list[bool]:
        """Whether each cube, then the handle, touches both fingers: one vectorised pass
        over the contacts (iterating ``data.contact`` in Python costs about 10 us per
        contact)."""
        geoms = [*self.cube_geoms, self.handle_geom]
        pairs = data.contact.geom  # (ncon, 2)
        if not len(pairs):
            return [False] * len(geoms)
        bodies = model.geom_bodyid[pairs]  # (ncon, 2)
        left = (bodies == self.left_finger)[:, ::-1]  # the other side of each pair
        right = (bodies == self.right_finger)[:, ::-1]
        grasped = []
        for geom in geoms:
            side = pairs == geom
            grasped.append(bool((side & left).any() and (side & right).any()))
        return grasped

    def read(self, model: mujoco.MjModel, data: mujoco.MjData) -> WorldState:
        """Read the world state from the simulator (copies, never aliases ``data``)."""
        *grasps, handle_grasped = self._grasped(model, data)
        cubes = []
        for adr, grasped in zip(self.cube_qposes, grasps, strict=True):
            c = data.qpos[adr : adr + 7].tolist()
            cubes.append(CubeState((c[0], c[1], c[2]), (c[3], c[4], c[5], c[6]), grasped))
        first = cubes[0]
        valve = model.body_pos[self.valve_body]
        return WorldState(
            door_opening=float(data.qpos[self.door_qpos]),
            valve_angle=float(data.qpos[self.valve_qpos]),
            cube_pos=first.pos,
            cube_quat=first.quat,
            cube_grasped=first.grasped,
            handle_grasped=handle_grasped,
            more_cubes=tuple(cubes[1:]),
            valve_pos=(float(valve[0]), float(valve[1])),
        )
