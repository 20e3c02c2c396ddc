"""Object frames: nodes that move with their object, and skills that act in its frame.

A node anchored to an object (``Node.anchor``) lies at its declared position shifted by the
object's displacement from its ``nominal`` place, in the plane (objects rest on surfaces,
so only x and y move). A skill acts in the frame of its ``end`` node's object, if any: its
policy sees the TCP relative to the object (the observation's position minus the
displacement), its waypoints and termination shift with the object, and its data are
recorded in that frame. A skill ending at a fixed node acts in the world frame, whatever
its start.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

from osg_control.domain.base import Domain
from osg_control.domain.spec import Node, ObjectFrame, SkillSpec
from osg_control.errors import PlacementError

Offsets = Mapping[str, np.ndarray]
"""Object name -> its displacement (3-D, z = 0) from its nominal place [m]."""


def skill_frame(domain: Domain, skill: SkillSpec) -> str | None:
    """The object whose frame the skill acts in: its end node's anchor (None: world)."""
    return domain.nodes[skill.end].anchor


def node_position(nodes: Mapping[str, Node], name: str, offsets: Offsets) -> np.ndarray:
    """Where a node of ``nodes`` is, its anchor's displacement applied."""
    node = nodes[name]
    position = np.asarray(node.position, dtype=float)
    if node.anchor is not None and node.anchor in offsets:
        position = position + offsets[node.anchor]
    return position


def skill_offset(domain: Domain, skill: SkillSpec, offsets: Offsets) -> np.ndarray:
    """The displacement of the skill's frame (zeros in the world frame)."""
    frame = skill_frame(domain, skill)
    if frame is None or frame not in offsets:
        return np.zeros(3)
    return np.asarray(offsets[frame], dtype=float)


def in_skill_frame(obs: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """An observation with its TCP position relative to a frame displaced by ``offset``."""
    if not np.any(offset):
        return obs
    shifted = np.array(obs, dtype=float)
    shifted[..., :3] -= offset
    return shifted


def displacement(frame: ObjectFrame, x: float, y: float) -> np.ndarray:
    """An object's displacement from its nominal place when it lies at (x, y)."""
    return np.array([x - frame.nominal[0], y - frame.nominal[1], 0.0])


def reading_displacement(frame: ObjectFrame, values: Sequence[float]) -> np.ndarray:
    """An object's displacement from its values of ``frame.position_fields``: its (x, y),
    or its travel along ``frame.axis``."""
    if frame.axis is None:
        return displacement(frame, float(values[0]), float(values[1]))
    travel = float(values[0])
    return np.array([travel * frame.axis[0], travel * frame.axis[1], 0.0])


def offsets_of(
    objects: Sequence[ObjectFrame], world_fields: Sequence[str], world: np.ndarray
) -> dict[str, np.ndarray]:
    """Each object's displacement in a world vector (named by ``world_fields``). A
    vector stored before an object's fields were appended (shorter than ``world_fields``)
    has none for it: the object is left out (at its nominal place, ``node_position``)."""
    index = {name: i for i, name in enumerate(world_fields)}
    return {
        frame.name: reading_displacement(frame, [world[index[f]] for f in frame.position_fields])
        for frame in objects
        if all(index[f] < len(world) for f in frame.position_fields)
    }


PLACEMENT_DRAWS = 1000
"""Draws of one object's place before ``sample_placements`` gives up on clearing the
others."""


def sample_placements(
    domain: Domain | Sequence[ObjectFrame], rng: np.random.Generator, collecting: bool = False
) -> dict[str, np.ndarray]:
    """A uniform placement of every placed object (``ObjectFrame.placed``) in its region
    (x, y, and its resting z), each clear of those placed before it (``clearance``: drawn
    again until it is); the others stay where the scene has them. One object, or objects
    that clear each other at the first draw, take one draw each. An ``evaluation_only``
    object draws from a generator spawned from ``rng`` (``Generator.spawn`` draws nothing
    from it), and is left where the scene has it when ``collecting`` (Algorithm 1).

    Raises:
        PlacementError: an object not cleared of the others in ``PLACEMENT_DRAWS`` draws
            (more objects than its region fits).
    """
    frames = domain.objects if isinstance(domain, Domain) else domain
    placed: dict[str, np.ndarray] = {}
    clear: list[tuple[np.ndarray, float]] = []
    for frame in frames:
        if not frame.placed or (collecting and frame.evaluation_only):
            continue
        assert frame.region_low is not None and frame.region_high is not None  # placed
        draws = rng.spawn(1)[0] if frame.evaluation_only else rng
        for _draw in range(PLACEMENT_DRAWS):
            xy = draws.uniform(frame.region_low, frame.region_high)
            if all(np.hypot(*(xy - at)) >= r + frame.clearance for at, r in clear):
                break
        else:
            raise PlacementError(
                f"cannot place {frame.name!r} in its region {frame.region_low}-"
                f"{frame.region_high} {frame.clearance} m clear of {len(clear)} other "
                f"object(s) in {PLACEMENT_DRAWS} draws: the region fits no more"
            )
        placed[frame.name] = np.array([xy[0], xy[1], frame.rest_z])
        clear.append((xy, frame.clearance))
    return placed


def placement_offsets(
    objects: Sequence[ObjectFrame], placements: Mapping[str, np.ndarray]
) -> dict[str, np.ndarray]:
    """The displacement of each placed object (name -> position) from its nominal place."""
    frames = {frame.name: frame for frame in objects}
    return {
        name: displacement(frames[name], float(pos[0]), float(pos[1]))
        for name, pos in placements.items()
    }


def shifted_skill(skill: SkillSpec, offset: np.ndarray) -> SkillSpec:
    """The skill with its waypoints moved by ``offset`` (Algorithm 1 aiming at an object
    that lies ``offset`` from its nominal place)."""
    if not np.any(offset):
        return skill
    waypoints = tuple(
        replace(w, position=_xyz(np.asarray(w.position) + offset)) for w in skill.waypoints
    )
    return replace(skill, waypoints=waypoints)


def shifted_nodes(domain: Domain, offsets: Offsets) -> dict[str, Node]:
    """The domain's nodes where they are now (anchored ones moved with their objects)."""
    if not any(np.any(v) for v in offsets.values()):
        return dict(domain.nodes)
    return {
        name: replace(node, position=_xyz(node_position(domain.nodes, name, offsets)))
        for name, node in domain.nodes.items()
    }


def _xyz(values: np.ndarray) -> tuple[float, float, float]:
    """A position as the three floats a ``Node`` or ``Waypoint`` holds."""
    return float(values[0]), float(values[1]), float(values[2])
