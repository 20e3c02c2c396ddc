"""Checks that a ``Domain``'s fields refer to each other: run when it is built, so a
domain with a dangling name, an empty field or out-of-range bounds is refused at once,
naming the field."""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from osg_control.domain.benchmark import validate_benchmark
from osg_control.domain.spaces import ACTION_DIM
from osg_control.domain.spec import check_skill_fields
from osg_control.errors import DomainError, SkillSpecError

if TYPE_CHECKING:
    from osg_control.domain.base import Domain


def validate_domain(domain: Domain) -> None:
    """Check a domain's fields refer to each other correctly.

    Raises:
        DomainError: naming the domain and the field at fault.
    """
    where = f"domain {domain.name!r}"
    for attr in ("name", "nodes", "facts", "skills", "world_fields", "hand_empty"):
        if not getattr(domain, attr):
            raise DomainError(f"{where}: field {attr!r} is empty")
    if not callable(domain.facts_of) or not callable(domain.make_env):
        raise DomainError(f"{where}: fields 'facts_of' and 'make_env' must be callable")
    rate = domain.own_control_hz
    if (domain.robot is None) == (rate is None):
        raise DomainError(
            f"{where}: set exactly one of 'robot' (a robot's env) and 'own_control_hz' "
            "(an env that drives its own arm)"
        )
    if rate is not None and not (math.isfinite(rate) and rate > 0):
        raise DomainError(f"{where}: field 'own_control_hz' must be a positive rate [Hz]")
    facts = set(domain.facts)
    names = [s.name for s in domain.skills]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise DomainError(f"{where}: field 'skills' has duplicate names {duplicates}")
    for node_name, node in domain.nodes.items():
        if node.name != node_name:
            raise DomainError(f"{where}: field 'nodes' key {node_name!r} names {node.name!r}")
    for skill in domain.skills:
        try:
            check_skill_fields(skill)
        except SkillSpecError as err:
            raise DomainError(f"{where}: field 'skills': {err}") from err
        for role in ("start", "end"):
            if getattr(skill, role) not in domain.nodes:
                raise DomainError(
                    f"{where}: skill {skill.name!r} field {role!r} names unknown node "
                    f"{getattr(skill, role)!r}; nodes: {sorted(domain.nodes)}"
                )
        unknown = sorted(skill.facts - facts)
        if unknown:
            raise DomainError(f"{where}: skill {skill.name!r} names unknown facts {unknown}")
    unknown = sorted(set(domain.training) - set(names))
    if unknown:
        raise DomainError(f"{where}: field 'training' names unknown skills {unknown}")
    _check_objects(where, domain)
    for field_name, named in fact_fields(domain):
        unknown = sorted({f for f in named if not f.startswith("(")} - facts)
        if unknown:  # atoms over objects, (in-cabinet cube-2), are checked once lifted
            raise DomainError(f"{where}: field {field_name!r} names unknown facts {unknown}")
    if domain.home not in domain.nodes:
        raise DomainError(f"{where}: field 'home' names unknown node {domain.home!r}")
    for task in domain.tasks:
        if not task.goal:
            raise DomainError(f"{where}: task {task.name!r} has an empty goal")
        if task.node and task.node not in domain.nodes:
            raise DomainError(f"{where}: task {task.name!r} names unknown node {task.node!r}")
    bounds = np.asarray(domain.action_bounds, dtype=float)
    if bounds.shape != (ACTION_DIM,) or not (np.all(np.isfinite(bounds)) and np.all(bounds > 0)):
        raise DomainError(
            f"{where}: field 'action_bounds' must be 7 positive finite numbers, got "
            f"{domain.action_bounds!r}"
        )
    if not (math.isfinite(domain.step_cost) and domain.step_cost >= 0):
        raise DomainError(f"{where}: field 'step_cost' must be >= 0, got {domain.step_cost!r}")
    if domain.benchmark is not None:
        validate_benchmark(domain.benchmark, domain.facts, where)


def fact_fields(domain: Domain) -> list[tuple[str, Iterable[str]]]:
    """Every field that names facts (by name, or as atoms over the domain's objects); a
    task of other object counts than the domain's is left to the domain of its scene."""
    fields: list[tuple[str, Iterable[str]]] = [
        ("start_world", domain.start_world),
        ("watched_facts", domain.watched_facts),
        ("hand_empty", (domain.hand_empty,)),
    ]
    for task in domain.tasks:
        if not domain.runs_here(task):
            continue  # checked in the domain of its scene (``Domain.for_task``)
        fields += [
            (f"tasks[{task.name}].goal", task.goal),
            (f"tasks[{task.name}].world", task.world),
        ]
    fields += [(f"start_regions[{r.name}].facts", r.facts) for r in domain.start_regions]
    return fields


def _check_objects(where: str, domain: Domain) -> None:
    """Anchors and instances name declared objects; an object's fields are the domain's
    (its held fact is checked against the lifted view, ``Domain.__post_init__``)."""
    objects = {o.name: o for o in domain.objects}
    for node in domain.nodes.values():
        if node.anchor is not None and node.anchor not in objects:
            raise DomainError(
                f"{where}: node {node.name!r} field 'anchor' names unknown object "
                f"{node.anchor!r}; objects: {sorted(objects)}"
            )
    for instance in domain.instances:
        if instance.frame is not None and instance.frame not in objects:
            raise DomainError(
                f"{where}: instance {instance.name!r} field 'frame' names unknown object "
                f"{instance.frame!r}; objects: {sorted(objects)}"
            )
    for frame in domain.objects:
        unknown = sorted(set(frame.position_fields) - set(domain.world_fields))
        if unknown:
            raise DomainError(
                f"{where}: object {frame.name!r} names unknown world fields {unknown}"
            )
        if len(frame.position_fields) != (1 if frame.axis is not None else 2):
            raise DomainError(
                f"{where}: object {frame.name!r} field 'position_fields' must name "
                + ("its travel (one field, with 'axis')" if frame.axis else "its x and y")
                + f", got {list(frame.position_fields)}"
            )
        if (frame.region_low is None) != (frame.region_high is None):
            raise DomainError(f"{where}: object {frame.name!r} has one placement corner")
        if frame.placed and not all(
            lo <= hi for lo, hi in zip(frame.region_low or (), frame.region_high or (), strict=True)
        ):
            raise DomainError(f"{where}: object {frame.name!r} has an empty placement region")
