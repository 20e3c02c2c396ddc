"""The kitchen as a ``Domain``: its nodes, facts, skills, tasks, start regions and env."""

from __future__ import annotations

from typing import Any

import numpy as np

from osg_control.domain.base import Domain, StartRegion
from osg_control.kitchen.objects import FACT_ATOMS, INSTANCES, PREDICATES, TYPES
from osg_control.kitchen.paper import PUBLISHED
from osg_control.kitchen.scene import ROBOT_MOUNTS
from osg_control.kitchen.skills import NODES, OBJECTS, SKILLS, WORLD_FACTS
from osg_control.kitchen.tasks import DEFAULT_WORLD, KITCHEN_TASKS
from osg_control.kitchen.world import WORLD_FIELDS, world_facts, world_state_from_array
from osg_control.paths import PACKAGE_DIR

DEFAULT_ROBOT = "panda"
"""The robot the kitchen is built around unless told otherwise (registry name)."""
MEETING_NODES: tuple[str, ...] = ("home", "above-cube", "door-front", "cabinet-front")
"""Where the movement skills meet: four of the paper's eight start regions."""
WATCHED_FACTS = frozenset({"holding-cube"})
"""Preconditions watched while a skill that keeps them runs; losing one stops the skill. In
the offline data the cube's grasp holds on every step of pick-up-cube and
move-cube-to-cabinet and drops out for at most 3 steps in place-cube-in-cabinet, so a loss
means a dropped cube. holding-handle is not watched: the slide pushes the handle with one
finger, so the both-finger contact is off on 94 % of its steps."""
REACH_FACTS = ("door-open",)
"""The reach table (III) starts with the door open: every movement skill's path is then
clear of the handle."""


REGION_EDGES: tuple[tuple[str, str], ...] = (
    ("above-cube", "cabinet-front"),
    ("above-cube", "home"),
    ("cabinet-front", "home"),
    ("door-front", "home"),
)
"""The movement edges whose midpoints are start regions: the 4 longest of the paper's graph
(far from every node). Fixed, so that growing the graph (e.g. the valve's edge) keeps
Tables III-V comparable."""


def start_regions() -> tuple[StartRegion, ...]:
    """The paper's 8 start regions (Table III): the 4 meeting nodes and the midpoints of
    ``REGION_EDGES``."""
    regions = [StartRegion(name, NODES[name].position, facts=REACH_FACTS) for name in MEETING_NODES]
    for a, b in REGION_EDGES:
        mid = (np.asarray(NODES[a].position) + NODES[b].position) / 2
        position = (float(mid[0]), float(mid[1]), float(mid[2]))
        regions.append(StartRegion(f"mid({a},{b})", position, facts=REACH_FACTS))
    return tuple(regions)


def facts_of(world: np.ndarray) -> frozenset[str]:
    """The kitchen's facts of a world-state vector (``world.WORLD_FIELDS``)."""
    return world_facts(world_state_from_array(world))


def make_kitchen_env(**kwargs: Any) -> Any:
    """A ``KitchenEnv`` (imported here: MuJoCo loads only when an env is made)."""
    from osg_control.kitchen.env import KitchenEnv

    return KitchenEnv(**kwargs)


def kitchen_domain() -> Domain:
    """The kitchen domain (registered as ``kitchen``)."""
    return Domain(
        name="kitchen",
        description="MuJoCo kitchen: a sliding-door cabinet, a cube and a valve around a robot",
        nodes=NODES,
        facts=WORLD_FACTS,
        skills=SKILLS,
        tasks=KITCHEN_TASKS,
        start_regions=start_regions(),
        start_world=DEFAULT_WORLD,
        home="home",
        world_fields=WORLD_FIELDS,
        facts_of=facts_of,
        make_env=make_kitchen_env,
        hand_empty="hand-empty",
        watched_facts=WATCHED_FACTS,
        objects=OBJECTS,
        perceptions=("paper", "robot", "sim", "camera"),
        defaults_dir=PACKAGE_DIR / "kitchen" / "defaults",
        env_id="osg/Kitchen-v0",
        published=PUBLISHED,
        robot=DEFAULT_ROBOT,
        mounts=ROBOT_MOUNTS,
        types=TYPES,
        instances=INSTANCES,
        predicates=PREDICATES,
        fact_atoms=FACT_ATOMS,
    )
