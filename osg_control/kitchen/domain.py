"""The kitchen as a ``Domain``: its nodes, facts, skills, tasks, start regions and env."""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial
from typing import Any

import numpy as np

from osg_control.domain.base import Domain, StartRegion
from osg_control.errors import DomainError
from osg_control.kitchen.cubes import check_cubes, cube_objects
from osg_control.kitchen.objects import (
    FACT_ATOMS,
    PREDICATES,
    TYPES,
    cube_fact,
    cube_instances,
    world_fact_names,
)
from osg_control.kitchen.paper import PUBLISHED
from osg_control.kitchen.scene import ROBOT_MOUNTS
from osg_control.kitchen.skills import NODES, SKILLS, TRAINING
from osg_control.kitchen.tasks import DEFAULT_WORLD, KITCHEN_TASKS
from osg_control.kitchen.world import world_facts, world_fields, world_state_from_array
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
    """The kitchen's facts of a world-state vector (``world.world_fields``, any number of
    cubes)."""
    return world_facts(world_state_from_array(world))


def make_kitchen_env(**kwargs: Any) -> Any:
    """A ``KitchenEnv`` (imported here: MuJoCo loads only when an env is made)."""
    from osg_control.kitchen.env import KitchenEnv

    return KitchenEnv(**kwargs)


def kitchen_domain(cubes: int = 1) -> Domain:
    """The kitchen domain (registered as ``kitchen``) with ``cubes`` cubes in its scene
    (1 to ``objects.MAX_CUBES``; ``kitchen[cube=2]``, ``Domain.with_counts``): the one-cube
    kitchen lists every task, each of the others the tasks of its count.

    Raises:
        DomainError: a cube count out of range.
    """
    try:
        check_cubes(cubes)
    except ValueError as err:
        raise DomainError(f"domain 'kitchen': {err}") from None
    counts = () if cubes == 1 else (("cube", cubes),)
    tasks = tuple(t for t in KITCHEN_TASKS if cubes == 1 or t.counts == counts)
    more = range(2, cubes + 1)
    return Domain(
        name="kitchen",
        description="MuJoCo kitchen: a sliding-door cabinet, cubes and a valve around a robot",
        nodes=NODES,
        facts=world_fact_names(cubes),
        skills=SKILLS,
        training=TRAINING,
        tasks=tasks,
        start_regions=start_regions(),
        start_world=DEFAULT_WORLD + tuple(cube_fact("cube-on-counter", k) for k in more),
        home="home",
        world_fields=world_fields(cubes),
        facts_of=facts_of,
        make_env=partial(make_kitchen_env, cubes=cubes) if cubes > 1 else make_kitchen_env,
        hand_empty="hand-empty",
        watched_facts=WATCHED_FACTS,
        objects=cube_objects(cubes),
        perceptions=("paper", "robot", "sim", "camera"),
        defaults_dir=PACKAGE_DIR / "kitchen" / "defaults",
        env_id="osg/Kitchen-v0",
        published=PUBLISHED,
        robot=DEFAULT_ROBOT,
        mounts=ROBOT_MOUNTS,
        types=TYPES,
        instances=cube_instances(cubes),
        predicates=PREDICATES,
        fact_atoms=FACT_ATOMS,
        scaled=scaled_kitchen,
        counts=counts,
    )


def scaled_kitchen(counts: Mapping[str, int]) -> Domain:
    """The kitchen with ``counts`` objects (``Domain.scaled``): only its cubes vary.

    Raises:
        DomainError: a type other than ``cube``, or a cube count out of range.
    """
    other = sorted(set(counts) - {"cube"})
    if other:
        raise DomainError(f"domain 'kitchen': only the number of cubes varies, not {other}")
    return kitchen_domain(int(counts.get("cube", 1)))
