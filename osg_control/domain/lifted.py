"""Typed objects, predicates over them, and skills as lifted operators.

A domain may declare object types (``Domain.types``: type -> parent), the object
instances of its scene (``ObjectInstance``), predicates with typed parameters
(``PredicateDecl``) and, once per world fact, the ground atom the fact is
(``FactAtom``: ``cube-lifted`` is ``(lifted cube-1)``). The facts its ``facts_of`` returns
and its specs name stay these names; everything lifted is derived here:

* an atom's **fact name**: the declared fact whose atom it is, else its PDDL form
  (``(lifted cube-2)``), or its bare name for a 0-ary predicate without a declaration (so a
  domain that declares nothing is a valid lifted domain of 0-ary predicates);
* a skill with typed ``SkillSpec.parameters`` (``grab-cube(?c - cube)``) is written for
  the **recorded binding**: each parameter bound to the first instance of its type (the
  object its data were recorded with). Its lifted operator replaces those instances by
  the variables; the other instances it names stay constants;
* where the robot is: ``(at NODE)`` for a fixed node; ``(at-object NODE OBJ)`` for a
  node anchored to an object frame (``Node.anchor``) that an instance carries
  (``ObjectInstance.frame``), i.e. the node relative to that object;
* ``domain.binding`` grounds a lifted skill for other instances (a plan step).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from osg_control.domain.spec import Node, SkillSpec
from osg_control.errors import DomainError, PlanningError

OBJECT_TYPE = "object"
"""The root type: every type and instance is an object."""
NODE_TYPE = "node"
"""The type of the graph's nodes (PDDL constants)."""
AT = "at"
"""``(at NODE)``: the robot is at a fixed node."""
AT_OBJECT = "at-object"
"""``(at-object NODE OBJ)``: the robot is at a node anchored to the object ``OBJ``."""

Atom = tuple[str, ...]
"""A ground or lifted atom: predicate name, then objects or ``?variables``."""


@dataclass(frozen=True)
class ObjectInstance:
    """An object of the scene.

    Attributes:
        name: its PDDL name (e.g. ``cube-1``).
        type: its type (a key of ``Domain.types``).
        frame: the ``ObjectFrame`` that locates it (nodes anchored to that frame are
            relative to this instance), or None.
    """

    name: str
    type: str
    frame: str | None = None


@dataclass(frozen=True)
class PredicateDecl:
    """A predicate and its typed parameters, e.g. ``PredicateDecl("lifted", (("c",
    "cube"),))`` for ``(lifted ?c - cube)``."""

    name: str
    parameters: tuple[tuple[str, str], ...] = ()

    @property
    def arity(self) -> int:
        """How many arguments it takes."""
        return len(self.parameters)


@dataclass(frozen=True)
class FactAtom:
    """A world fact's ground atom: the fact ``name`` is ``(predicate *args)``."""

    name: str
    predicate: str
    args: tuple[str, ...] = ()

    @property
    def atom(self) -> Atom:
        """The atom as a tuple."""
        return (self.predicate, *self.args)


def _is_atom(fact: str) -> bool:
    """Whether a fact name is written as an atom, ``(on-counter cube-2)``."""
    return fact.startswith("(")


def atom_text(atom: Atom) -> str:
    """An atom in PDDL syntax: ``(lifted cube-1)``."""
    return "(" + " ".join(atom) + ")"


@dataclass(frozen=True)
class LiftedSkill:
    """A skill as a lifted operator (names in PDDL normal form, variables as ``?x``).

    Attributes:
        name: the skill (operator) name.
        parameters: ``(?variable, type)`` in order.
        recorded: the instance of each parameter the spec is written for (``?var`` ->
            instance).
        start, end: where the robot is before and after (``(at n)`` or ``(at-object n ?o)``).
        pre, add, delete: the lifted world atoms.
    """

    name: str
    parameters: tuple[tuple[str, str], ...]
    recorded: Mapping[str, str]
    start: Atom
    end: Atom
    pre: tuple[Atom, ...]
    add: tuple[Atom, ...]
    delete: tuple[Atom, ...]

    @property
    def atoms(self) -> tuple[Atom, ...]:
        """Every atom it names."""
        return (self.start, self.end, *self.pre, *self.add, *self.delete)


class Lifting:
    """The lifted view of one domain's declarations (see the module docstring).

    Args:
        types: type -> parent type (``object`` implicit).
        instances: the scene's objects.
        predicates: the declared predicates.
        fact_atoms: the declared facts' atoms.
        facts: every fact name of the domain (undeclared ones are 0-ary predicates).
        nodes: the graph's nodes.
        skills: the skill specs.

    Raises:
        DomainError: a declaration names an unknown type, predicate, instance or frame,
            has a wrong arity or type, or is declared twice.
    """

    def __init__(
        self,
        types: Mapping[str, str],
        instances: Sequence[ObjectInstance],
        predicates: Sequence[PredicateDecl],
        fact_atoms: Sequence[FactAtom],
        facts: Sequence[str],
        nodes: Mapping[str, Node],
        skills: Sequence[SkillSpec],
    ) -> None:
        self.types = {name: parent or OBJECT_TYPE for name, parent in types.items()}
        self.instances = {i.name: i for i in instances}
        declared = {f.name: f for f in fact_atoms}
        self.predicates = {p.name: p for p in predicates}
        for name in facts:  # an undeclared fact is its own 0-ary predicate, or an atom
            if name not in declared and name not in self.predicates and not _is_atom(name):
                self.predicates[name] = PredicateDecl(name)
        self._atom = {name: f.atom for name, f in declared.items()}
        self._name = {atom: name for name, atom in self._atom.items()}
        self.nodes = nodes
        self._check(instances, predicates, fact_atoms, facts)
        self.skills = {s.name: self._lift(s) for s in skills}

    # ----- declarations -------------------------------------------------------------

    def _check(
        self,
        instances: Sequence[ObjectInstance],
        predicates: Sequence[PredicateDecl],
        fact_atoms: Sequence[FactAtom],
        facts: Sequence[str],
    ) -> None:
        for what, names in (
            ("instances", [i.name for i in instances]),
            ("predicates", [p.name for p in predicates]),
            ("fact_atoms", [f.name for f in fact_atoms]),
        ):
            twice = sorted({n for n in names if names.count(n) > 1})
            if twice:
                raise DomainError(f"field {what!r} declares {twice} twice")
        for name, parent in self.types.items():
            if name in (OBJECT_TYPE, NODE_TYPE) or parent not in {*self.types, OBJECT_TYPE}:
                raise DomainError(
                    f"field 'types': type {name!r} (parent {parent!r}) is reserved or has an "
                    f"unknown parent; types: {sorted(self.types)}"
                )
            seen, ancestor = {name}, parent
            while ancestor != OBJECT_TYPE:
                if ancestor in seen:
                    raise DomainError(f"field 'types': type {name!r} is its own ancestor")
                seen.add(ancestor)
                ancestor = self.types[ancestor]
        for instance in instances:
            if instance.type not in self.types:
                raise DomainError(
                    f"instance {instance.name!r} has unknown type {instance.type!r}; types: "
                    f"{sorted(self.types)}"
                )
        for predicate in predicates:
            for _var, kind in predicate.parameters:
                if kind != OBJECT_TYPE and kind not in self.types:
                    raise DomainError(f"predicate {predicate.name!r} names unknown type {kind!r}")
        for name in facts:
            if _is_atom(name):  # a fact written as its atom: (on-counter cube-2)
                try:
                    self.check_atom(self.atom(name))
                except PlanningError as err:
                    raise DomainError(f"fact {name!r}: {err}") from None
        for fact in fact_atoms:
            if fact.name not in facts:
                raise DomainError(f"fact_atoms: {fact.name!r} is not one of the domain's facts")
            try:
                self.check_atom(fact.atom)
            except PlanningError as err:
                raise DomainError(f"fact {fact.name!r}: {err}") from None
        atoms = [f.atom for f in fact_atoms]
        twice = sorted({atom_text(a) for a in atoms if atoms.count(a) > 1})
        if twice:
            raise DomainError(f"fact_atoms: atoms {twice} are declared for two facts")

    def is_a(self, kind: str, ancestor: str) -> bool:
        """Whether ``kind`` is ``ancestor`` or one of its subtypes."""
        while True:
            if kind == ancestor:
                return True
            if kind == OBJECT_TYPE:
                return False
            kind = self.types.get(kind, OBJECT_TYPE)

    def of_type(self, kind: str) -> list[str]:
        """The instances of ``kind`` (subtypes included), in declaration order."""
        return [i.name for i in self.instances.values() if self.is_a(i.type, kind)]

    def instance_of_frame(self, frame: str | None) -> str | None:
        """The instance an object frame locates, if one declares it."""
        if frame is None:
            return None
        return next((i.name for i in self.instances.values() if i.frame == frame), None)

    @property
    def lifted(self) -> bool:
        """Whether anything takes arguments (else every predicate is 0-ary)."""
        return bool(self.instances) or any(p.arity for p in self.predicates.values())

    # ----- atoms and fact names -------------------------------------------------------

    def atom(self, fact: str) -> Atom:
        """The atom of a fact name (declared, ``(pred args)``, or a bare 0-ary name).

        Raises:
            PlanningError: an unreadable fact.
        """
        if fact in self._atom:
            return self._atom[fact]
        text = fact.strip()
        if text.startswith("(") and text.endswith(")"):
            text = text[1:-1]
        parts = tuple(text.split())
        if not parts or "(" in text or ")" in text:
            raise PlanningError(f"cannot read a fact from {fact!r}")
        return self.resolve(parts)

    def resolve(self, atom: Atom) -> Atom:
        """An atom as a user may write it, in the planner's terms: a declared fact's name
        (bare or ``(name)``) is its atom, ``(at NODE)`` of an anchored node is
        ``(at-object NODE OBJ)``; anything else is itself."""
        if len(atom) == 1:
            return self._atom.get(atom[0], atom)
        if atom[0] == AT and len(atom) == 2 and atom[1] in self.nodes:
            return self.place(atom[1])
        return atom

    def fact(self, atom: Atom) -> str:
        """The fact name of a ground atom (see the module docstring)."""
        if atom in self._name:
            return self._name[atom]
        return atom[0] if len(atom) == 1 else atom_text(atom)

    def check_atom(self, atom: Atom) -> None:
        """Check a ground atom: a declared predicate, its arity, known objects of the
        parameters' types (``at``/``at-object`` over nodes and instances included).

        Raises:
            PlanningError: naming the unknown predicate or object, or the wrong arity.
        """
        name, args = atom[0], atom[1:]
        if name == AT:
            expected: tuple[tuple[str, str], ...] = (("n", NODE_TYPE),)
        elif name == AT_OBJECT:
            expected = (("n", NODE_TYPE), ("o", OBJECT_TYPE))
        elif name in self.predicates:
            expected = self.predicates[name].parameters
        else:
            named = f"; facts: {', '.join(self._atom)}" if self._atom else ""
            raise PlanningError(
                f"unknown predicate {name!r} in {atom_text(atom)}; known predicates: "
                f"{', '.join(sorted({*self.predicates, AT}))}{named}"
            )
        if len(args) != len(expected):
            raise PlanningError(
                f"predicate {name!r} takes {len(expected)} argument(s), got {len(args)} in "
                f"{atom_text(atom)}"
            )
        for arg, (_var, kind) in zip(args, expected, strict=True):
            if kind == NODE_TYPE:
                if arg not in self.nodes:
                    raise PlanningError(
                        f"unknown node {arg!r} in {atom_text(atom)}; nodes: {', '.join(self.nodes)}"
                    )
                continue
            if arg not in self.instances:
                raise PlanningError(
                    f"unknown object {arg!r} in {atom_text(atom)}; known objects: "
                    f"{', '.join(self.instances) or '(none)'}"
                )
            if not self.is_a(self.instances[arg].type, kind):
                raise PlanningError(
                    f"object {arg!r} in {atom_text(atom)} is a {self.instances[arg].type}, "
                    f"not a {kind}"
                )

    def ground_fact(self, fact: str) -> str:
        """A fact as written by a user (a name, ``(name)`` or ``(pred args)``), checked and
        in the domain's fact names.

        Raises:
            PlanningError: an unknown predicate or object, or a wrong arity.
        """
        atom = self.atom(fact)
        self.check_atom(atom)
        return self.fact(atom)

    def place(self, node: str) -> Atom:
        """Where the robot is at ``node``: ``(at node)`` or ``(at-object node obj)``."""
        instance = self.instance_of_frame(self.nodes[node].anchor)
        return (AT, node) if instance is None else (AT_OBJECT, node, instance)

    # ----- skills -----------------------------------------------------------------------

    def recorded_binding(self, name: str, parameters: Sequence[tuple[str, str]]) -> dict[str, str]:
        """Each parameter's recorded instance (``?var`` -> the first of its type).

        Raises:
            DomainError: a parameter of an unknown type, or of a type without instances.
        """
        binding = {}
        for var, kind in parameters:
            found = self.of_type(kind)
            if not found:
                raise DomainError(
                    f"skill {name!r} parameter ?{var} has type {kind!r} without an "
                    f"instance; types with instances: "
                    f"{sorted({i.type for i in self.instances.values()})}"
                )
            binding[f"?{var}"] = found[0]
        if len(set(binding.values())) != len(binding):
            raise DomainError(f"skill {name!r}: two parameters of one instance")
        return binding

    def _lift(self, skill: SkillSpec) -> LiftedSkill:
        return self.lift(
            skill.name,
            skill.parameters,
            skill.start,
            skill.end,
            skill.preconditions,
            skill.add_effects,
            skill.del_effects,
        )

    def lift(
        self,
        name: str,
        parameters: Sequence[tuple[str, str]],
        start: str,
        end: str,
        pre: Iterable[str],
        add: Iterable[str],
        delete: Iterable[str],
    ) -> LiftedSkill:
        """A skill (or a graph's edge of one) as a lifted operator: its facts' atoms with
        each parameter's recorded instance replaced by the parameter."""
        recorded = self.recorded_binding(name, parameters)
        variable = {obj: var for var, obj in recorded.items()}

        def lift(atom: Atom) -> Atom:
            return (atom[0], *(variable.get(a, a) for a in atom[1:]))

        def lifted(facts: Iterable[str]) -> tuple[Atom, ...]:
            return tuple(lift(self.atom(f)) for f in sorted(facts))

        return LiftedSkill(
            name=name,
            parameters=tuple((f"?{var}", kind) for var, kind in parameters),
            recorded=recorded,
            start=lift(self.place(start)),
            end=lift(self.place(end)),
            pre=lifted(pre),
            add=lifted(add),
            delete=lifted(delete),
        )

    def constants(self) -> list[str]:
        """The instances the lifted skills name as constants (not through a parameter)."""
        named = {
            arg
            for lifted in self.skills.values()
            for atom in lifted.atoms
            for arg in atom[1:]
            if arg in self.instances
        }
        return [name for name in self.instances if name in named]
