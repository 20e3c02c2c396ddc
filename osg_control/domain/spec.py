"""The data a skill graph is made of: nodes, waypoints, Algorithm 1 parameters, skill specs.

A skill is an option <I, pi, beta, effects>: it starts at the pose of its ``start`` node
(initiation region I: within ``start_radius`` of it), follows a scripted waypoint sequence
when collecting data (Algorithm 1), and terminates (beta) at its ``end`` node's pose with the
node's gripper state. World facts (PDDL predicates) are its preconditions and effects.

Poses are TCP positions in the robot base frame [m] with an orientation (``w, x, y, z``);
the default ``TOP_DOWN_QUAT`` points the tool z axis down with the fingers closing along
world y. Nothing here knows any particular scene: a domain (``osg_control.domain.base``)
lists its nodes, facts and skills with these types.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass, field
from typing import Any, Literal

import numpy as np

from osg_control.errors import SkillSpecError
from osg_control.json_files import parse_json

TOP_DOWN_QUAT = (0.0, 1.0, 0.0, 0.0)
"""The default TCP orientation: a half turn about x (z down, y flipped)."""
MOVEMENT = "movement"
"""The skill kind the core treats specially: contact-free moves between meeting nodes, the
classifier's classes and the way onto the graph from anywhere."""

Gripper = Literal["open", "closed"]
_PDDL_NAME = re.compile(r"[a-z][a-z0-9_-]*")
"""A PDDL name in normal form (a parameter's variable or type)."""
Quat = tuple[float, float, float, float]


@dataclass(frozen=True)
class Node:
    """A named TCP pose of the skill graph: position [m], gripper state, orientation.

    ``anchor`` names the object (``ObjectFrame``) the node moves with: its ``position`` is
    given for the object at its ``nominal`` place and shifts with the object's perceived
    displacement in the plane (``domain.frames``); None: a fixed pose.
    """

    name: str
    position: tuple[float, float, float]
    gripper: Gripper = "open"
    orientation: Quat = TOP_DOWN_QUAT
    anchor: str | None = None


@dataclass(frozen=True)
class ObjectFrame:
    """An object that nodes may be anchored to, and where it may be placed.

    Attributes:
        name: the object (as the nodes' ``anchor`` names it).
        position_fields: the world fields of its x and y position [m]; or, for an object
            that moves along a fixed track (a sliding door), the one field of its travel
            along ``axis`` [m].
        nominal: the (x, y) the anchored nodes' positions are given for [m] (a tracked
            object: its place at zero travel).
        rest_z: the height of its centre when it rests where it is placed [m].
        region_low, region_high: the (x, y) corners of its placement region [m] (Algorithm
            1's random placements and ``--randomize-objects``); None: never placed at random
            (it moves only when the robot moves it).
        held_fact: the fact that holds while the robot holds it (its frame is then frozen
            where it was picked up): a fact name, or an atom over the domain's objects
            (``(holding cube-2)``), so each object's grasp is tracked on its own; None:
            never held.
        axis: the unit (x, y) direction of a tracked object's travel; None: placed freely
            in the plane (two ``position_fields``).
        clearance: the radius [m] it keeps clear around it where it is placed at random:
            two placed objects' centres are at least their clearances' sum apart (0: none).
        evaluation_only: placed at random only when evaluating (``--randomize-objects``),
            never by Algorithm 1 (its data recorded where the scene has it), its place drawn
            from a stream of its own (``frames.sample_placements``): an object made
            placeable after data were collected changes neither the data nor any other
            object's draws.
    """

    name: str
    position_fields: tuple[str, ...]
    nominal: tuple[float, float]
    rest_z: float = 0.0
    region_low: tuple[float, float] | None = None
    region_high: tuple[float, float] | None = None
    held_fact: str | None = None
    axis: tuple[float, float] | None = None
    clearance: float = 0.0
    evaluation_only: bool = False

    @property
    def placed(self) -> bool:
        """Whether Algorithm 1 and ``--randomize-objects`` place it at random."""
        return self.region_low is not None and self.region_high is not None


@dataclass(frozen=True)
class Waypoint:
    """One target of the scripted policy: TCP position [m] and gripper state to reach there.

    Attributes:
        position: TCP target [m].
        gripper: the gripper state to switch to once there.
        steps: overrides the script's ``steps_per_waypoint`` for this waypoint.
        reach: distance [m] within which the waypoint counts as reached, instead of the
            episode's drawn threshold.
        orientation: TCP orientation target (``w, x, y, z``); None keeps the default
            ``TOP_DOWN_QUAT``.
    """

    position: tuple[float, float, float]
    gripper: Gripper
    steps: int | None = None
    reach: float | None = None
    orientation: Quat | None = None


@dataclass(frozen=True)
class ScriptParams:
    """Algorithm 1's noise parameters for one skill (see ``osg_control.data.scripted``).

    Attributes:
        threshold_mean: mu_1, mean distance [m] below which a waypoint counts as reached.
        threshold_std: sigma_1 [m].
        noise_mean: mu_2, mean of the Gaussian noise added to every action component.
        noise_std: sigma_2, its standard deviation (position in m, angles in rad, gripper).
        steps_per_waypoint: the fixed step budget per waypoint.
    """

    threshold_mean: float = 0.01
    threshold_std: float = 0.005
    noise_mean: float = 0.0
    noise_std: float = 0.01
    steps_per_waypoint: int = 20


@dataclass(frozen=True)
class TrainingRecipe:
    """How a skill's shipped weights are made where they depart from a run's defaults, so
    ``osg reproduce`` and ``osg train`` make them the same way (``Domain.training``).

    Attributes:
        episodes_factor: the skill collects this many times the run's episodes per skill.
        obs_noise: std [m] of the training noise on the sampled TCP position
            (``TD3BCConfig.obs_noise``): for a skill that acts within a few steps of its
            start, before a filtered reading settles.
    """

    episodes_factor: int = 1
    obs_noise: float = 0.0

    def __post_init__(self) -> None:
        if not (isinstance(self.episodes_factor, int) and self.episodes_factor >= 1):
            raise ValueError(f"episodes_factor must be a whole number >= 1, got "
                             f"{self.episodes_factor!r}")  # fmt: skip
        if not (math.isfinite(self.obs_noise) and self.obs_noise >= 0):
            raise ValueError(f"obs_noise must be finite and >= 0 [m], got {self.obs_noise!r}")


@dataclass(frozen=True)
class SkillSpec:
    """A skill: its graph edge, script, success predicate and symbolic pre/effects.

    Attributes:
        name: lower-case hyphenated, also its PDDL operator name.
        kind: ``"movement"`` (no contact, see ``MOVEMENT``) or a domain's own label.
        start: the node whose pose is the centre of the initiation region.
        end: the node whose pose is the termination condition beta.
        waypoints: positions and gripper states the scripted policy visits in order.
        preconditions: world facts that must hold to start (besides being at ``start``).
        add_effects: world facts the skill makes true.
        del_effects: world facts the skill makes false.
        start_facts: world facts its data are recorded in beyond the domain's default
            start world (the domain's scene sets them up); the executor enters a skill
            from off the graph only where they hold.
        holding: the object the skill starts holding (a domain's name), if any.
        success_tolerance: TCP distance to ``end`` [m] within which beta holds.
        script: Algorithm 1's parameters for data collection.
        max_steps: the step budget of a learned policy's episode.
        start_radius: radius [m] of the random starts around ``start``.
        start_angle: per-axis orientation range [rad] of the random starts.
        parameters: its typed parameters as a lifted operator, ``(variable, type)`` (e.g.
            ``(("c", "cube"),)`` for ``grab-cube(?c - cube)``); its facts are written for
            the first instance of each type (``domain.lifted``).
    """

    name: str
    kind: str
    start: str
    end: str
    waypoints: tuple[Waypoint, ...]
    preconditions: frozenset[str] = frozenset()
    add_effects: frozenset[str] = frozenset()
    del_effects: frozenset[str] = frozenset()
    start_facts: frozenset[str] = frozenset()
    holding: str | None = None
    success_tolerance: float = 0.02
    script: ScriptParams = field(default_factory=ScriptParams)
    max_steps: int = 80
    start_radius: float = 0.02
    start_angle: float = 0.05
    parameters: tuple[tuple[str, str], ...] = ()

    @property
    def is_movement(self) -> bool:
        """A contact-free move between meeting nodes (a classifier class)."""
        return self.kind == MOVEMENT

    @property
    def facts(self) -> frozenset[str]:
        """Every world fact the spec names."""
        return self.preconditions | self.add_effects | self.del_effects | self.start_facts

    def waypoint_budgets(self, params: ScriptParams | None = None) -> list[int]:
        """Algorithm 1's step budget of each waypoint: its own ``steps``, else the
        script's (``params``, default the skill's) ``steps_per_waypoint``."""
        per_waypoint = (params or self.script).steps_per_waypoint
        return [w.steps or per_waypoint for w in self.waypoints]

    def to_json(self) -> str:
        """Serialise (for data-set attributes and checkpoint sidecars): what the skill is
        recorded as. ``parameters`` are left out: they are the planner's view of the same
        recorded skill (lifting it changes no episode), so data and checkpoints recorded
        before a skill was lifted stay that skill's (``osg collect`` keeps them)."""
        data = asdict(self)
        del data["parameters"]
        for key in ("preconditions", "add_effects", "del_effects", "start_facts"):
            data[key] = sorted(data[key])
        return json.dumps(data, sort_keys=True)


def check_skill_fields(skill: SkillSpec) -> None:
    """Check the fields a spec can get wrong by itself (not the nodes or facts it names).

    Raises:
        SkillSpecError: naming the skill and the field at fault.
    """
    if not skill.waypoints:
        raise SkillSpecError(f"skill {skill.name!r}: field 'waypoints' is empty")
    for i, waypoint in enumerate(skill.waypoints):
        if not np.all(np.isfinite(waypoint.position)) or len(waypoint.position) != 3:
            raise SkillSpecError(
                f"skill {skill.name!r}: field 'waypoints[{i}].position' must be 3 finite "
                f"numbers, got {waypoint.position}"
            )
        if waypoint.steps is not None and waypoint.steps < 1:
            raise SkillSpecError(
                f"skill {skill.name!r}: field 'waypoints[{i}].steps' must be >= 1, "
                f"got {waypoint.steps}"
            )
        if waypoint.reach is not None and not waypoint.reach > 0:
            raise SkillSpecError(
                f"skill {skill.name!r}: field 'waypoints[{i}].reach' must be > 0, "
                f"got {waypoint.reach}"
            )
    for name in ("success_tolerance", "start_radius", "start_angle"):
        value = getattr(skill, name)
        if not (np.isfinite(value) and value >= 0):
            raise SkillSpecError(f"skill {skill.name!r}: field {name!r} must be >= 0, got {value}")
    if skill.max_steps < 1:
        raise SkillSpecError(f"skill {skill.name!r}: field 'max_steps' must be >= 1")
    well_formed = all(
        isinstance(p, tuple) and len(p) == 2 and all(_PDDL_NAME.fullmatch(str(v)) for v in p)
        for p in skill.parameters
    )
    variables = [p[0] for p in skill.parameters] if well_formed else []
    if not well_formed or len(set(variables)) != len(variables):
        raise SkillSpecError(
            f"skill {skill.name!r}: field 'parameters' must be distinct (variable, type) "
            f"names, got {skill.parameters!r}"
        )


def skill_from_json(text: str | Mapping[str, Any]) -> SkillSpec:
    """Rebuild a spec from ``SkillSpec.to_json`` output, checking its fields.

    Raises:
        SkillSpecError: a missing or malformed field, named.
    """
    try:
        data = dict(parse_json(text) if isinstance(text, str) else text)
    except (TypeError, ValueError) as err:
        raise SkillSpecError(f"skill spec is not JSON: {err}") from err
    name = data.get("name", "<unnamed>")
    try:
        waypoints = tuple(
            Waypoint(
                tuple(w["position"]),
                w["gripper"],
                w.get("steps"),
                w.get("reach"),
                tuple(w["orientation"]) if w.get("orientation") is not None else None,
            )
            for w in data.pop("waypoints")
        )
        script = ScriptParams(**data.pop("script"))
        for key in ("preconditions", "add_effects", "del_effects", "start_facts"):
            data[key] = frozenset(data.get(key, ()))
        data["parameters"] = tuple(tuple(p) for p in data.get("parameters", ()))
        skill = SkillSpec(waypoints=waypoints, script=script, **data)
    except (KeyError, TypeError, ValueError) as err:
        raise SkillSpecError(f"skill {name!r}: missing or malformed field: {err}") from err
    check_skill_fields(skill)
    return skill


def nearest_start(
    skills: Iterable[SkillSpec], nodes: Mapping[str, Node], position: np.ndarray
) -> SkillSpec:
    """The skill whose start node is nearest to a TCP position [m] (first on ties)."""
    return min(
        skills,
        key=lambda s: float(np.linalg.norm(position - np.asarray(nodes[s.start].position))),
    )
