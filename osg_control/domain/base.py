"""The ``Domain`` interface: everything the generic OSG core needs to know about a scene.

A domain is data plus two functions: its nodes, world facts, skill specs, tasks and start
regions; an env factory (the paper's 10-D state, 7-D relative TCP action); the names of
its world-state fields and ``facts_of(world)``, the predicate function that abstracts a
world state into PDDL facts; which fact means "hand empty" and which facts a running skill
must keep (a lost one stops the skill); where its shipped defaults live. The core
(collection, learning, graph, PDDL, planning, classifier, execution, evaluation) takes a
``Domain`` as an argument and never imports one; ``osg_control.domain.registry`` finds
them by name.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from osg_control.control.description import ORIGIN, Placement, mounted
from osg_control.domain.benchmark import Benchmark
from osg_control.domain.lifted import FactAtom, Lifting, ObjectInstance, PredicateDecl
from osg_control.domain.spaces import (
    PAPER_ACTION_BOUNDS,
    CheckedEnvFactory,
    observation_bounds,
    unbounded_observation,
)
from osg_control.domain.spec import Node, ObjectFrame, SkillSpec, TrainingRecipe
from osg_control.domain.validation import fact_fields, validate_domain
from osg_control.errors import DomainError, PlanningError, SkillSpecError, lookup
from osg_control.perception.spec import SIMULATED_PERCEPTIONS


@dataclass(frozen=True)
class Task:
    """A task of a domain: goal facts from a start world.

    Attributes:
        name: hyphenated (also the PDDL problem's name and file name).
        goal: the world facts to reach.
        world: the world facts at the start (empty: the domain's ``start_world``).
        node: the graph node the PDDL problem starts at (evaluations start anywhere).
        description: one line for humans.
        counts: how many objects of a type its scene holds, ``(("cube", 2),)``, where it
            is not the domain's own scene (``Domain.for_task``); empty: the domain's.
    """

    name: str
    goal: tuple[str, ...]
    world: tuple[str, ...] = ()
    node: str = ""
    description: str = ""
    counts: tuple[tuple[str, int], ...] = ()


@dataclass(frozen=True)
class StartRegion:
    """A region of random starts for the reach table (III) and the task tables (IV/V).

    Attributes:
        name: shown in the tables.
        position: the centre [m] of the random starts.
        radius: their radius [m].
        angle: their per-axis orientation range [rad].
        facts: world facts the reach table starts in (beyond the start world), e.g. a
            world where every movement skill's path is clear.
    """

    name: str
    position: tuple[float, float, float]
    radius: float = 0.15
    angle: float = 0.2
    facts: tuple[str, ...] = ()


EnvFactory = Callable[..., Any]
"""``make_env(skill=None, config=None, render_mode=None)``: a Gymnasium env of the domain
implementing ``domain.contract.SkillEnv`` (e.g. an ``osg_control.environment.ArmEnv``)."""


class ImportSummary(Protocol):
    """What an outside layout's import did."""

    def to_json(self) -> dict[str, Any]:
        """The summary as a JSON-ready dict (``--json``)."""
        ...

    def lines(self) -> list[str]:
        """The summary for humans, one line each."""
        ...


@dataclass(frozen=True)
class DatasetLayout:
    """An outside data-set layout a domain imports (``osg datasets import --layout NAME``).

    Attributes:
        name: the ``--layout`` value.
        detects: whether a Minari data set (folder or id) has this layout (``auto``).
        imports: ``(domain, source, out folder) -> summary``: writes the domain's data set
            files; refuses a malformed source before writing anything.
    """

    name: str
    detects: Callable[[str], bool]
    imports: Callable[[Domain, str, Path], ImportSummary]


@dataclass(frozen=True)
class Domain:
    """One scene and its skill graph, as data for the generic core (see module docstring).

    Attributes:
        name: registry key (``osg --domain NAME``), also the PDDL domain's name suffix.
        description: one line for humans.
        nodes: node name -> pose.
        facts: the world facts' names (each a 0-ary predicate unless ``fact_atoms``
            declares its atom).
        skills: the skill specs (their order does not matter: seeds come from names).
        tasks: named goals.
        start_regions: random-start regions of Tables III-V.
        start_world: the world facts of a task's start unless the task says otherwise.
        home: the node a task's PDDL problem starts at unless the task says otherwise.
        world_fields: the names of the world-state vector's entries.
        facts_of: world-state vector -> the facts that hold.
        make_env: the env factory (see ``EnvFactory``); the domain wraps it so that every
            env it builds is checked against the domain (``spaces.CheckedEnvFactory``:
            the contract, the spaces, ``action_bounds`` and ``perceptions``).
        hand_empty: the fact meaning nothing is held.
        watched_facts: preconditions a running skill must keep (lost: the skill stops).
        defaults_dir: the shipped skills and classifier (``skills/``, ``classifier/``,
            ``manifest.json``), or None if the domain ships none.
        env_id: the Gymnasium id its env is registered under, if any.
        objects: the objects nodes may be anchored to (``Node.anchor``), with their
            placement regions.
        perceptions: the perceptions (``perception.spec.PERCEPTIONS``) its env simulates;
            the first is the default of every command that runs episodes.
        published: published figures to report beside ours (see
            ``osg_control.evaluation.report.PUBLISHED_KEYS``).
        benchmark: an outside benchmark's protocol on this domain's env (``osg evaluate
            benchmark``), if any.
        action_bounds: the per-step bound of each of the 7 action components (m, rad,
            gripper), declared here only: its env clips to them, scripted collection,
            training and the data-set exports scale by them (default: the paper's 2 cm and
            0.1 rad, ``spaces.PAPER_ACTION_BOUNDS``).
        step_cost: plan cost per step of a skill's Algorithm 1 budget, added to its
            ``round(-ln p * 1000)`` (0: plans minimise failure only; a domain whose env has
            an episode step limit prefers the shorter of two likely plans with it).
        dataset_layouts: outside data-set layouts it imports (``DatasetLayout``).
        own_control_hz: the control rate [Hz] of an env that drives its own arm (``robot``
            None); a robot's env steps at its robot's rate. ``control_hz`` gives either;
            data-set exports and recordings time their frames by it.
        robot: the registered robot (``osg_control.robots``) its env drives by default,
            which ``make_env(robot=NAME)`` replaces; None: its env drives its own arm and no
            other robot can be chosen.
        robot_is_default: whether ``robot`` is the domain's own (False after
            ``with_robot`` chose another).
        mounts: where a robot's base stands in its scene, by robot name (a robot not
            named stands at the origin); ``with_robot`` builds the env around the robot so
            mounted (``description.mounted``), IK and readouts in scene coordinates.
        types: object types, type -> parent type (``"object"`` the root).
        instances: the objects of its scene (``lifted.ObjectInstance``).
        predicates: predicates with typed parameters (``lifted.PredicateDecl``); a fact
            without a ``fact_atoms`` entry is a 0-ary predicate of its own name.
        fact_atoms: each fact's ground atom (``lifted.FactAtom``: ``cube-lifted`` is
            ``(lifted cube-1)``). ``lifting`` derives the lifted operators from these.
        scaled: builds the domain with another number of objects of a type in its scene
            (``{"cube": 2}`` -> the domain with two cubes: its instances, facts, world
            fields, objects and env), if its scene can; ``with_counts`` calls it.
        counts: the object counts it was built with by ``with_counts`` (empty: its own
            scene); part of its ``ref``. Its tasks of other counts are checked and run in
            the domain of theirs (``for_task``).
        training: skill name -> how its weights are made where that departs from a run's
            defaults (``spec.TrainingRecipe``: more episodes, training noise); read by
            ``osg reproduce`` and ``osg train``.
    """

    name: str
    description: str
    nodes: Mapping[str, Node]
    facts: tuple[str, ...]
    skills: tuple[SkillSpec, ...]
    tasks: tuple[Task, ...]
    start_regions: tuple[StartRegion, ...]
    start_world: tuple[str, ...]
    home: str
    world_fields: tuple[str, ...]
    facts_of: Callable[[np.ndarray], frozenset[str]]
    make_env: EnvFactory
    hand_empty: str
    watched_facts: frozenset[str] = frozenset()
    defaults_dir: Path | None = None
    env_id: str | None = None
    perceptions: tuple[str, ...] = SIMULATED_PERCEPTIONS
    objects: tuple[ObjectFrame, ...] = ()
    published: Mapping[str, Any] = field(default_factory=dict)
    benchmark: Benchmark | None = None
    action_bounds: tuple[float, ...] = PAPER_ACTION_BOUNDS
    step_cost: float = 0.0
    dataset_layouts: tuple[DatasetLayout, ...] = ()
    own_control_hz: float | None = None
    robot: str | None = None
    robot_is_default: bool = True
    mounts: Mapping[str, Placement] = field(default_factory=dict)
    types: Mapping[str, str] = field(default_factory=dict)
    instances: tuple[ObjectInstance, ...] = ()
    predicates: tuple[PredicateDecl, ...] = ()
    fact_atoms: tuple[FactAtom, ...] = ()
    scaled: Callable[[Mapping[str, int]], Domain] | None = None
    counts: tuple[tuple[str, int], ...] = ()
    training: Mapping[str, TrainingRecipe] = field(default_factory=dict)
    skills_by_name: dict[str, SkillSpec] = field(init=False, repr=False, compare=False)
    lifting: Lifting = field(init=False, repr=False, compare=False)
    """The lifted view of its declarations (``domain.lifted``)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "skills_by_name", {s.name: s for s in self.skills})
        validate_domain(self)
        try:
            lifting = Lifting(
                self.types,
                self.instances,
                self.predicates,
                self.fact_atoms,
                self.facts,
                self.nodes,
                self.skills,
            )
        except DomainError as err:
            raise DomainError(f"domain {self.name!r}: {err}") from None
        atoms = [
            (f"objects[{o.name}].held_fact", (o.held_fact,))
            for o in self.objects
            if o.held_fact is not None
        ]
        for field_name, named in [*fact_fields(self), *atoms]:
            for fact in named:  # a fact's name, or an atom over its objects: (holding cube-2)
                try:
                    lifting.ground_fact(fact)
                except PlanningError as err:
                    raise DomainError(
                        f"domain {self.name!r}: field {field_name!r} names unknown fact "
                        f"{fact!r} ({err})"
                    ) from None
        object.__setattr__(self, "lifting", lifting)
        factory = self.make_env  # replace() passes the checked one: re-wrapped, not nested
        if isinstance(factory, CheckedEnvFactory):
            factory = factory.factory
        checked = CheckedEnvFactory(
            factory, self.name, tuple(self.action_bounds), tuple(self.perceptions)
        )
        object.__setattr__(self, "make_env", checked)

    def with_robot(self, robot: str) -> Domain:
        """This domain with its env built around the registered robot ``robot``, at its
        mount (``mounts``).

        Another robot than the domain's own has its own artifacts (``ref``) and the
        shipped defaults of ``<defaults_dir>-<robot>`` if the domain ships them (none
        otherwise: the default robot's policies do not drive another arm). It is checked
        to reach the domain's nodes and skill waypoints first (``domain.reach``).

        Raises:
            DomainError: the domain's env drives its own arm (``robot`` is None).
            UnreachableError: the robot, at its mount, does not reach a node or waypoint.
        """
        if self.robot is None:
            raise DomainError(
                f"domain {self.name!r}: its env drives its own arm; no robot can be chosen"
            )
        if robot == self.robot:
            return self
        checked = self.make_env
        own_factory = checked.factory if isinstance(checked, CheckedEnvFactory) else checked
        defaults = None
        if self.defaults_dir is not None:
            defaults = self.defaults_dir.with_name(f"{self.defaults_dir.name}-{robot}")
        from osg_control.domain.reach import check_reach
        from osg_control.robots.registry import get_robot

        description = mounted(get_robot(robot), self.mounts.get(robot, ORIGIN))
        check_reach(self, description)
        return replace(
            self,
            robot=robot,
            robot_is_default=False,
            make_env=partial(own_factory, robot=description),
            defaults_dir=defaults if defaults is not None and defaults.is_dir() else None,
        )

    def with_counts(self, counts: Mapping[str, int]) -> Domain:
        """This domain with ``counts`` objects of each type named (e.g. ``{"cube": 2}``):
        itself for its own counts, else ``scaled``'s domain (with this one's robot).

        Raises:
            DomainError: the domain cannot change its objects (no ``scaled``), or its
                ``scaled`` refuses the counts (e.g. more cubes than its scene fits).
        """
        wanted = tuple(sorted((str(kind), int(n)) for kind, n in counts.items()))
        own = self.counts or tuple(
            sorted((kind, len(self.lifting.of_type(kind))) for kind, _ in wanted)
        )
        if wanted == own or not wanted:
            return self
        if self.scaled is None:
            raise DomainError(f"domain {self.name!r} cannot change its objects to {dict(wanted)}")
        domain = replace(self.scaled(dict(wanted)), counts=wanted)
        return domain if self.robot_is_default else domain.with_robot(str(self.robot))

    def for_task(self, task: Task) -> Domain:
        """The domain whose scene a task runs in (``Task.counts``; itself if none)."""
        return self.with_counts(dict(task.counts)) if task.counts else self

    def runs_here(self, task: Task) -> bool:
        """Whether a task runs in this domain's own scene (its counts are this one's)."""
        return not task.counts or tuple(sorted(task.counts)) == self.counts

    @property
    def control_hz(self) -> float:
        """Its env's control rate [Hz]: one action per ``1 / control_hz`` s."""
        if self.own_control_hz is not None:
            return self.own_control_hz
        assert self.robot is not None  # validate_domain: one of the two is set
        from osg_control.robots.registry import get_robot

        return get_robot(self.robot).control_hz

    def observation_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Its env's 10-D state bounds: its robot's (``spaces.observation_bounds``), or
        unbounded for an env that drives its own arm."""
        if self.robot is None:
            return unbounded_observation()
        from osg_control.robots.registry import get_robot

        return observation_bounds(get_robot(self.robot))

    @property
    def ref(self) -> str:
        """How the domain is found again: ``name``, or ``name@robot`` with another robot
        than its own (``with_robot``). ``registry.get_domain`` takes it, so a worker in a
        fresh process (Ray's) rebuilds the same robot's domain; it also names the folder
        of its artifacts under the cache; ``name[cube=2]`` names its object counts
        (``with_counts``)."""
        counts = ",".join(f"{kind}={n}" for kind, n in self.counts)
        name = f"{self.name}[{counts}]" if counts else self.name
        return name if self.robot_is_default else f"{name}@{self.robot}"

    def recipe(self, name: str) -> TrainingRecipe:
        """How skill ``name``'s weights are made (``training``; the defaults if unsaid)."""
        return self.training.get(self.skill(name).name, TrainingRecipe())

    def skill(self, name: str) -> SkillSpec:
        """Look a skill up by name.

        Raises:
            SkillSpecError: for an unknown name, listing the known ones.
        """
        return lookup(
            self.skills_by_name,
            name,
            "skill",
            lambda m: SkillSpecError(f"domain {self.name!r}: {m}"),
        )

    def task(self, name: str) -> Task:
        """Look a task up by name.

        Raises:
            DomainError: for an unknown name, listing the known ones.
        """
        tasks = {t.name: t for t in self.tasks}
        return lookup(tasks, name, "task", lambda m: DomainError(f"domain {self.name!r}: {m}"))

    @property
    def movement_skills(self) -> tuple[SkillSpec, ...]:
        """The contact-free moves between meeting nodes (the classifier's classes)."""
        return tuple(s for s in self.skills if s.is_movement)

    def node_of(self, skill: SkillSpec, role: str) -> Node:
        """The start (``role="start"``) or end node of a skill."""
        return self.nodes[skill.start if role == "start" else skill.end]

    def task_world(self, task: Task) -> tuple[str, ...]:
        """The start facts of a task (its own, else the domain's start world)."""
        return task.world or self.start_world

    def task_node(self, task: Task) -> str:
        """The node a task's PDDL problem starts at."""
        return task.node or self.home

    def summary(self) -> dict[str, Any]:
        """A JSON-ready description (``osg domains --json``; ``summary.domain_summary``)."""
        from osg_control.domain.summary import domain_summary

        return domain_summary(self)
