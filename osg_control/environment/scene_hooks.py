"""``SceneHooks``: what a domain's env tells ``ArmEnv`` about its scene (the model, the
world-state readout and its facts, start worlds, objects, what a start may hold), with the
defaults of a scene that has none of the optional parts."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.domain.spec import Node, ObjectFrame


class SceneHooks:
    """The scene's part of ``ArmEnv`` (see ``docs/domains.md``): subclasses implement
    ``build_model``, ``read_world`` and ``facts_of``, may override the other hooks, and
    declare ``world_facts``, ``world_options``, ``holdable``, ``objects`` and
    ``world_sensors``."""

    robot: RobotDescription
    nodes: dict[str, Node]

    world_facts: tuple[str, ...] = ()
    """The facts ``facts_of`` can give: the ``facts`` reset option may name only these
    (empty: not declared; a fact the start world lacks is refused all the same)."""
    world_options: tuple[str, ...] = ()
    """The entries the ``world`` reset option may have (``check_world`` checks the values)."""
    holdable: tuple[str, ...] = ()
    """What a start may hold (the ``holding`` reset option)."""
    objects: tuple[ObjectFrame, ...] = ()
    """The objects nodes may be anchored to (the domain's ``objects``)."""
    world_sensors: dict[str, str] = {}
    """World field -> the sensor kind that reads it (``perception.sensors``), in the order of
    ``read_world``'s vector."""

    def build_model(self) -> mujoco.MjModel:
        """The compiled scene with ``self.robot``, a ``home`` keyframe and an ``overview``
        camera (``control.scene_model``)."""
        raise NotImplementedError

    def read_world(self) -> np.ndarray:
        """The world-state vector (the domain's ``world_fields``), a fresh array."""
        raise NotImplementedError

    def facts_of(self, world: np.ndarray) -> frozenset[str]:
        """The domain's facts that hold in a world-state vector."""
        raise NotImplementedError

    def check_world(self, world: dict[str, Any], holding: str | None) -> None:
        """Refuse explicit ``world`` reset options (their names are ``world_options``) that
        mean nothing (e.g. non-finite) or contradict ``holding``.

        Raises:
            EnvOptionError: naming the option and its value.
        """

    def place_world(
        self, world: dict[str, Any], facts: frozenset[str], holding: str | None
    ) -> None:
        """Put the scene's objects in place for a start (the arm is already placed and its
        kinematics computed): ``world`` holds explicit options, ``facts`` the start facts."""

    def placement_offsets(self, world: dict[str, Any]) -> dict[str, np.ndarray]:
        """The displacement of each object the ``world`` reset option places (moves the
        start of a skill whose start node is anchored to it)."""
        return {}

    def placement_world(
        self, placements: dict[str, np.ndarray], holding: str | None
    ) -> dict[str, Any]:
        """The ``world`` reset options that put the objects at ``placements`` (those not
        held: a held object is placed in the fingers)."""
        return {}

    def detect_world(self, state: np.ndarray, world: np.ndarray) -> np.ndarray:
        """The perceived world with its ``detected`` fields recomputed from the percepts
        (``state``: the perceived 10-D state; e.g. a grasp from the finger width and the
        object's perceived pose)."""
        return world

    def snap_start(
        self,
        pos: np.ndarray,
        rot: np.ndarray,
        holding: str | None,
        world: dict[str, Any],
        facts: frozenset[str],
    ) -> tuple[np.ndarray, np.ndarray]:
        """Adjust a sampled start pose so that a start holding an object is consistent."""
        return pos, rot

    def held_geoms(self, holding: str | None) -> set[int]:
        """Geoms the robot may touch at a start holding ``holding``."""
        return set()

    def finger_opening(self, holding: str) -> float:
        """Finger joint position [m] at a start holding ``holding``."""
        return 0.0
