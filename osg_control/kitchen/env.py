"""``KitchenEnv``: the kitchen scene around a robot (``ArmEnv`` with the kitchen's world).

The world-state vector is ``world.world_fields(cubes)`` (door travel, valve angle, each
cube's pose, which objects both fingers touch, the valve's place); its facts are
``world.world_facts``. The scene holds ``cubes`` cubes (1 to ``objects.MAX_CUBES``; a
constructor argument, since the cubes are bodies of the compiled model and the world
vector's width follows them). A start world is given by facts (``door-open`` slides the
door to ``skills.DOOR_OPENED``) or explicitly with the ``world`` reset option
(``door_opening`` [m], ``cube_pos``, ``cube2_pos`` ..., ``valve_pos``: the valve's (x, y),
``valve.py``); ``holding`` is ``"cube"`` (cube 1) or ``"handle"``. The robot is
``DEFAULT_ROBOT`` unless another is given (any registered ``RobotDescription`` with a
two-finger gripper).
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.control.robot_model import workspace
from osg_control.domain.frames import placement_offsets, reading_displacement
from osg_control.domain.spec import ObjectFrame, SkillSpec
from osg_control.environment.arm_env import ArmEnv, EnvConfig
from osg_control.errors import SkillSpecError, lookup
from osg_control.kitchen.cameras import kitchen_cameras
from osg_control.kitchen.cubes import check_cubes, cube_objects, cube_sensors
from osg_control.kitchen.detectors import WORLD_SENSORS, detect_grasps
from osg_control.kitchen.domain import DEFAULT_ROBOT, facts_of
from osg_control.kitchen.objects import world_fact_names
from osg_control.kitchen.options import check_world_options, cube_option, world_options
from osg_control.kitchen.scene import SceneIndex, build_kitchen_model, kitchen_robot
from osg_control.kitchen.skills import DOOR, DOOR_OPENED, NODES, SKILLS_BY_NAME
from osg_control.kitchen.valve import VALVE, VALVE_SENSORS, valve_position
from osg_control.kitchen.world import CUBE_HALF_SIZE, WorldState

HANDLE_GRASP_SLACK = 0.015
"""How far along the handle fin [m] (x) a handle-holding start may grasp it: about the
offset a grab under 2 cm observation noise ends with, so the slide's data covers it."""
_FINGER_ON = {"cube": CUBE_HALF_SIZE - 0.0005, "handle": 0.0095}
"""Finger joint position [m] with the fingers closed on the cube or the handle fin."""


class KitchenEnv(ArmEnv):
    """The kitchen with a robot driven by relative TCP commands (see ``ArmEnv``).

    Args:
        skill: the skill (or its name) whose reward and termination the env gives.
        config: noise, step budget, IK and random-start options.
        render_mode: ``"rgb_array"`` for ``render``.
        robot: a registered robot's name or a description (default ``DEFAULT_ROBOT``).
        cubes: how many cubes the scene holds (1 to ``objects.MAX_CUBES``; each its own
            colour, which the ``camera`` perception's masks find: ``cameras``).

    Raises:
        EnvOptionError: a cube count out of range.

    Example:
        >>> env = KitchenEnv(skill="move-home-to-cube")
        >>> obs, info = env.reset(seed=0)
        >>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    """

    holdable = tuple(_FINGER_ON)

    def __init__(
        self,
        skill: str | SkillSpec | None = None,
        config: EnvConfig | None = None,
        render_mode: str | None = None,
        robot: str | RobotDescription | None = None,
        cubes: int = 1,
    ) -> None:
        self.cubes = check_cubes(cubes)
        """How many cubes the scene holds."""
        self.camera_perception = kitchen_cameras(cubes)
        self.world_facts = world_fact_names(cubes)
        self.world_options = world_options(cubes)
        self.world_sensors = {**WORLD_SENSORS, **cube_sensors(cubes), **VALVE_SENSORS}
        self.objects = cube_objects(cubes)
        spec = (
            lookup(SKILLS_BY_NAME, skill, "skill", SkillSpecError)
            if isinstance(skill, str)
            else skill
        )  # anything else is checked (named) by ArmEnv
        robot = kitchen_robot(robot or DEFAULT_ROBOT)
        super().__init__(NODES, "home", spec, config or EnvConfig(), render_mode, robot=robot)
        self.scene = SceneIndex(self.model, robot, cubes)

    def build_model(self) -> mujoco.MjModel:
        """The kitchen with the env's robot and cubes (``scene.build_kitchen_model``)."""
        return build_kitchen_model(self.robot, self.cubes)

    def world(self) -> WorldState:
        """The kitchen's world state as named fields (door, valve, cubes, grasps)."""
        return self.scene.read(self.model, self.data)

    def read_world(self) -> np.ndarray:
        """``world.world_fields(cubes)`` of the current state."""
        return self.scene.read(self.model, self.data).as_array()

    facts_of = staticmethod(facts_of)
    """The domain's ``facts_of`` (``world.world_facts`` of a world-state vector)."""

    def _cube_options(self) -> dict[str, str]:
        """Each cube's frame -> the ``world`` option that places it."""
        return {frame.name: cube_option(k) for k, frame in enumerate(self._cube_frames(), 1)}

    def _cube_frames(self) -> list[ObjectFrame]:
        return [f for f in self.objects if f.name not in (DOOR.name, VALVE.name)]

    def _placing_options(self) -> dict[str, str]:
        """Each placed object's frame -> the ``world`` option that places it."""
        return {**self._cube_options(), VALVE.name: "valve_pos"}

    def placement_offsets(self, world: dict[str, Any]) -> dict[str, np.ndarray]:
        """Each cube's displacement when ``world`` places it (``cube_pos``, ``cube2_pos``
        ...), the valve's (``valve_pos``), the door's when it slides it (``door_opening``)."""
        placed = {
            frame: np.asarray(world[option], float)
            for frame, option in self._placing_options().items()
            if world.get(option) is not None
        }
        offsets = placement_offsets(self.objects, placed)
        if world.get("door_opening") is not None:
            offsets["door"] = reading_displacement(DOOR, [float(world["door_opening"])])
        return offsets

    def placement_world(
        self, placements: dict[str, np.ndarray], holding: str | None
    ) -> dict[str, Any]:
        """Each placed cube's option (``cube_pos`` ...), but cube 1's when it is held, and
        the valve's (x, y) (``valve_pos``)."""
        world = {
            option: [float(v) for v in placements[frame]]
            for frame, option in self._cube_options().items()
            if frame in placements and not (option == "cube_pos" and holding == "cube")
        }
        if VALVE.name in placements:
            world["valve_pos"] = [float(v) for v in placements[VALVE.name][:2]]
        return world

    def detect_world(self, state: np.ndarray, world: np.ndarray) -> np.ndarray:
        """The grasps from the finger width and the perceived poses
        (``detectors.detect_grasps``)."""
        return detect_grasps(state, world)

    def check_world(self, world: dict[str, Any], holding: str | None) -> None:
        """Refuse a non-finite or out-of-range ``door_opening`` or cube position, or two
        cubes overlapping (``options.check_world_options``)."""
        check_world_options(world, holding, workspace(self.robot), self.cubes)

    def place_world(
        self, world: dict[str, Any], facts: frozenset[str], holding: str | None
    ) -> None:
        """Put the valve where ``valve_pos`` says (else at the file's place: the model's
        body moves back every reset), slide the door (open if ``door-open`` is a start
        fact) and place the cubes (cube 1 in the fingers when held)."""
        self.model.body_pos[self.scene.valve_body] = valve_position(world)
        self.data.qpos[self.scene.door_qpos] = _door_opening(world, facts)
        options = self._cube_options().values()
        for adr, option in zip(self.scene.cube_qposes, options, strict=True):
            cube_pos = world.get(option)
            if holding == "cube" and option == "cube_pos":
                cube_pos = self.data.site_xpos[self._tcp].copy()
            if cube_pos is not None:
                self.data.qpos[adr : adr + 3] = cube_pos
                self.data.qpos[adr + 3 : adr + 7] = (1.0, 0.0, 0.0, 0.0)

    def snap_start(
        self,
        pos: np.ndarray,
        rot: np.ndarray,
        holding: str | None,
        world: dict[str, Any],
        facts: frozenset[str],
    ) -> tuple[np.ndarray, np.ndarray]:
        """A handle-holding start has the fin between the fingers, anywhere within
        ``HANDLE_GRASP_SLACK`` of the nominal grasp along it."""
        if holding != "handle":
            return pos, rot
        handle = NODES["handle"].position
        door = _door_opening(world, facts)
        snapped = np.array([handle[0], handle[1] + door, pos[2]])
        snapped[0] += np.clip(pos[0] - handle[0], -HANDLE_GRASP_SLACK, HANDLE_GRASP_SLACK)
        return snapped, _TOP_DOWN_MATRIX

    def held_geoms(self, holding: str | None) -> set[int]:
        """The cube's or the handle's geom."""
        if holding == "cube":
            return {self.scene.cube_geom}
        if holding == "handle":
            return {self.scene.handle_geom}
        return set()

    def finger_opening(self, holding: str) -> float:
        """Fingers closed on the cube or on the handle fin."""
        return _FINGER_ON[holding]


def _door_opening(world: dict[str, Any], facts: frozenset[str]) -> float:
    """The start's door travel [m]: the explicit ``world`` option, else open (``DOOR_OPENED``)
    when ``door-open`` is a start fact, else shut."""
    return float(world.get("door_opening", DOOR_OPENED if "door-open" in facts else 0.0))


_TOP_DOWN_MATRIX = np.diag([1.0, -1.0, -1.0])
"""``TOP_DOWN_QUAT`` as a rotation matrix (a half turn about x)."""
