"""Where the robot is on the skill graph: on a node, part-way along a manipulation skill's
path, or off the graph (the executor then classifies). Reads the perceived state only."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from osg_control.domain.base import Domain
from osg_control.domain.binding import bindings
from osg_control.domain.frames import (
    Offsets,
    node_position,
    shifted_skill,
    skill_offset,
)
from osg_control.domain.spec import SkillSpec
from osg_control.environment.success import GRIPPER_OPEN_CMD

NODE_TOLERANCE = 0.02
"""TCP distance [m] within which the robot counts as on a graph node or a skill's path."""


def node_at(
    domain: Domain, obs: np.ndarray, facts: Iterable[str], offsets: Offsets | None = None
) -> str | None:
    """The graph node the TCP is on (within ``NODE_TOLERANCE``, gripper matching), if any;
    anchored nodes where their objects are (``offsets``, see ``domain.frames``), and
    relative to each object of their object's type: ``above-cube cube-2`` (a planner's
    start, ``pddl_io.build_problem``).

    A node reached only while holding something counts only when the gripper is closed;
    empty-handed nodes only when the hand is empty (the domain's ``hand_empty`` fact).
    """
    facts = set(facts)
    offsets = offsets or {}
    gripper = "open" if obs[7] == GRIPPER_OPEN_CMD else "closed"
    best, best_distance = None, NODE_TOLERANCE
    for node in domain.nodes.values():
        if node.gripper != gripper or (gripper == "open") != (domain.hand_empty in facts):
            continue
        for name, frame in _anchors(domain, node.anchor):
            where = np.asarray(node.position, dtype=float)
            if frame is not None and frame in offsets:
                where = where + offsets[frame]
            distance = float(np.linalg.norm(obs[:3] - where))
            if distance <= best_distance:
                best = node.name if name is None else f"{node.name} {name}"
                best_distance = distance
    return best


def _anchors(domain: Domain, anchor: str | None) -> list[tuple[str | None, str | None]]:
    """Where a node anchored to ``anchor`` may be: ``(None, anchor)`` for the object its
    frame locates, then ``(object, its frame)`` for each other object of that type (a node
    relative to cube 2: ``above-cube cube-2``)."""
    recorded = domain.lifting.instance_of_frame(anchor)
    if recorded is None:
        return [(None, anchor)]
    instances = domain.lifting.instances
    others = [
        (name, instances[name].frame)
        for name in domain.lifting.of_type(instances[recorded].type)
        if name != recorded and instances[name].frame is not None
    ]
    return [(None, anchor), *others]


def recorded_world_holds(skill: SkillSpec, facts: Iterable[str]) -> bool:
    """Whether the world a skill's data was recorded in holds now: its ``start_facts`` (a
    skill recorded only in some world may run into what differs elsewhere)."""
    return skill.start_facts <= set(facts)


def _segment_distance(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance from a point to the segment a-b."""
    span = b - a
    length2 = float(span @ span)
    t = 0.0 if length2 == 0.0 else float(np.clip((point - a) @ span / length2, 0.0, 1.0))
    return float(np.linalg.norm(point - (a + t * span)))


def skill_on_path(
    domain: Domain,
    obs: np.ndarray,
    facts: Iterable[str],
    skills: Iterable[SkillSpec],
    offsets: Offsets | None = None,
) -> str | None:
    """The applicable manipulation skill whose scripted path the TCP is on, if any: its
    name, or ``skill obj`` when bound to another object than its recorded one (the path
    of ``grab-cube cube-2`` is where cube 2 is; its preconditions are cube 2's).

    A skill's path runs from its start node through its waypoints; on each leg the gripper
    is in the state it had on leaving (it switches only at a waypoint). Algorithm 1's data
    follows that path, so a state within ``NODE_TOLERANCE`` of a leg with the gripper
    matching is one the skill's policy was trained on: the skill can carry on from there
    (e.g. a grasp retried after the object slipped out). Movement skills are left to the
    classifier: their legs are shared by both directions of travel. A skill acting in an
    object's frame has its path where the object is (``offsets``).
    """
    facts = set(facts)
    offsets = offsets or {}
    gripper = "open" if obs[7] == GRIPPER_OPEN_CMD else "closed"
    position = np.asarray(obs[:3], dtype=float)
    best, best_distance = None, NODE_TOLERANCE
    for skill in skills:
        if skill.is_movement:
            continue
        for bound in bindings(domain.lifting, skill):
            if not bound.skill.preconditions <= facts:
                continue
            seen = bound.offsets(offsets)  # the object it is bound to, in its frame
            start_node = domain.nodes[skill.start]
            path = shifted_skill(skill, skill_offset(domain, skill, seen))
            stops = [(tuple(node_position(domain.nodes, skill.start, seen)), start_node.gripper)]
            stops += [(w.position, w.gripper) for w in path.waypoints]
            for (start, leg_gripper), (end, _) in zip(stops, stops[1:], strict=False):
                if leg_gripper != gripper:
                    continue
                distance = _segment_distance(position, np.asarray(start), np.asarray(end))
                if distance <= best_distance:
                    best = skill.name if not bound.frames and not bound.facts else bound.label
                    best_distance = distance
    return best
