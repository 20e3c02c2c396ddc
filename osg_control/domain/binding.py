"""Plan steps as bound skills: a lifted skill and the instances bound to its parameters.

The planner names a ground operator ``grab-cube cube-2``; ``bind_step`` turns it into a
``BoundSkill``: the spec with its facts for those objects, the object frames its policy
acts in, and the renaming of its facts (so a watched precondition is watched on the right
object). The policy is the lifted skill's: one per skill, learned in its object's frame.
With the recorded binding (each parameter the first instance of its type, what the spec is
written for) the bound skill is the spec itself.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from osg_control.domain.lifted import AT_OBJECT, Lifting
from osg_control.domain.spec import SkillSpec
from osg_control.errors import PlanningError


@dataclass(frozen=True)
class BoundSkill:
    """A plan step: a skill and the instances bound to its parameters.

    Attributes:
        skill: the spec with its facts for this binding (the spec itself for the
            recorded binding); its ``name`` is the lifted skill's, whose policy runs.
        binding: ``?var`` -> instance.
        frames: the object frames as the skill's policy sees them: the recorded
            instance's frame -> the bound instance's frame (where they differ).
        facts: the recorded binding's fact names -> this binding's, where they differ
            (e.g. a watched ``holding-cube`` is ``(holding cube-2)`` here).
    """

    skill: SkillSpec
    binding: Mapping[str, str] = field(default_factory=dict)
    frames: Mapping[str, str] = field(default_factory=dict)
    facts: Mapping[str, str] = field(default_factory=dict)

    @property
    def label(self) -> str:
        """``skill obj1 obj2`` as a planner names the ground operator (the skill's name
        alone without parameters)."""
        return " ".join([self.skill.name, *self.binding.values()])

    def fact(self, recorded: str) -> str:
        """A fact named for the recorded binding, for this binding."""
        return self.facts.get(recorded, recorded)

    def offsets(self, offsets: Mapping[str, Any]) -> dict[str, Any]:
        """Object displacements as the skill sees them: each recorded frame where its
        bound object is."""
        seen = dict(offsets)
        for old, new in self.frames.items():
            seen.pop(old, None)
            if new in offsets:
                seen[old] = offsets[new]
        return seen


def bind(lifting: Lifting, skill: SkillSpec, objects: Sequence[str]) -> BoundSkill:
    """The skill with its parameters bound to ``objects`` (in parameter order).

    Raises:
        PlanningError: the wrong number of objects, an unknown one, or one of another
            type.
    """
    lifted = lifting.skills[skill.name]
    if len(objects) != len(lifted.parameters):
        raise PlanningError(
            f"skill {skill.name!r} takes {len(lifted.parameters)} object(s), got {len(objects)}"
        )
    for obj, (var, kind) in zip(objects, lifted.parameters, strict=True):
        if obj not in lifting.instances or not lifting.is_a(lifting.instances[obj].type, kind):
            raise PlanningError(f"skill {skill.name!r}: {var} must be a {kind}, got {obj!r}")
    binding = {var: obj for (var, _), obj in zip(lifted.parameters, objects, strict=True)}
    if binding == dict(lifted.recorded):
        return BoundSkill(skill, binding)
    frames = {}
    for var, obj in binding.items():
        old = lifting.instances[lifted.recorded[var]].frame
        new = lifting.instances[obj].frame
        if old is not None and new is not None and old != new:
            frames[old] = new
    instead = {lifted.recorded[var]: obj for var, obj in binding.items()}

    def rename(fact: str) -> str:
        atom = lifting.atom(fact)
        return lifting.fact((atom[0], *(instead.get(a, a) for a in atom[1:])))

    facts = {fact: rename(fact) for fact in skill.facts}
    bound = replace(
        skill,
        preconditions=frozenset(facts[f] for f in skill.preconditions),
        add_effects=frozenset(facts[f] for f in skill.add_effects),
        del_effects=frozenset(facts[f] for f in skill.del_effects),
        start_facts=frozenset(facts[f] for f in skill.start_facts),
    )
    changed = {old: new for old, new in facts.items() if old != new}
    return BoundSkill(bound, binding, frames, changed)


def bind_step(lifting: Lifting, skills: Mapping[str, SkillSpec], step: str) -> BoundSkill:
    """A planner's ground operator name (``grab-cube cube-1``) as a bound skill.

    Raises:
        PlanningError: an unknown skill, or a binding ``bind`` refuses.
    """
    name, *objects = step.split()
    if name not in skills:
        raise PlanningError(f"plan step {step!r} names no skill of the domain")
    return bind(lifting, skills[name], objects)


def recorded(lifting: Lifting, skill: SkillSpec) -> BoundSkill:
    """The skill bound as its spec is written (its recorded binding)."""
    return BoundSkill(skill, dict(lifting.skills[skill.name].recorded))


def end_place(lifting: Lifting, bound: BoundSkill) -> str:
    """Where a bound skill ends, as a planner's start: its end node, or ``NODE OBJ`` for a
    node relative to another object than the recorded one (``above-cube cube-2``;
    ``pddl_io.build_problem``)."""
    lifted = lifting.skills[bound.skill.name]
    end = lifted.end
    moved = end[0] == AT_OBJECT and end[2] in bound.binding
    if moved and bound.binding[end[2]] != lifted.recorded[end[2]]:
        return f"{end[1]} {bound.binding[end[2]]}"
    return end[1]


def bindings(lifting: Lifting, skill: SkillSpec) -> list[BoundSkill]:
    """The skill bound to every assignment of distinct instances to its parameters, the
    recorded binding first."""
    lifted = lifting.skills[skill.name]
    choices: list[list[str]] = [[]]
    for _var, kind in lifted.parameters:
        choices = [[*c, obj] for c in choices for obj in lifting.of_type(kind) if obj not in c]
    return [bind(lifting, skill, objects) for objects in choices]
