"""The kitchen's objects and facts as typed PDDL: types, instances, predicates, and each
world fact's ground atom (declared once here; ``skills.WORLD_FACTS`` is derived).

A scene holds 1 to ``MAX_CUBES`` cubes. Cube 1 is the scene's own and its facts have names
(``cube-on-counter`` is ``(on-counter cube-1)``); cube k's facts are the same atoms over
``cube-k``, written as atoms (``(on-counter cube-2)``, ``cube_fact``).
"""

from __future__ import annotations

from dataclasses import replace

from osg_control.domain.lifted import FactAtom, ObjectInstance, PredicateDecl, atom_text

TYPES: dict[str, str] = {"cube": "object", "door": "object", "handle": "object", "valve": "object"}
"""Object types, each a direct subtype of ``object``."""
INSTANCES: tuple[ObjectInstance, ...] = (
    ObjectInstance("cube-1", "cube", frame="cube"),
    ObjectInstance("door-1", "door", frame="door"),
    ObjectInstance("handle-1", "handle"),
    ObjectInstance("valve-1", "valve", frame="valve"),
)
"""The scene's objects: one cube (located by the ``CUBE`` frame, which its nodes are
anchored to), the cabinet's sliding door (the ``DOOR`` frame: its travel, which the
``handle`` node follows), its handle and the valve (the ``VALVE`` frame: its place, which
its nodes follow)."""
PREDICATES: tuple[PredicateDecl, ...] = (
    PredicateDecl("hand-empty"),
    PredicateDecl("holding", (("o", "object"),)),
    PredicateDecl("door-open", (("d", "door"),)),
    PredicateDecl("door-closed", (("d", "door"),)),
    PredicateDecl("on-counter", (("c", "cube"),)),
    PredicateDecl("lifted", (("c", "cube"),)),
    PredicateDecl("in-cabinet", (("c", "cube"),)),
    PredicateDecl("valve-open", (("v", "valve"),)),
    PredicateDecl("valve-closed", (("v", "valve"),)),
)
FACT_ATOMS: tuple[FactAtom, ...] = (
    FactAtom("hand-empty", "hand-empty"),
    FactAtom("holding-handle", "holding", ("handle-1",)),
    FactAtom("holding-cube", "holding", ("cube-1",)),
    FactAtom("door-closed", "door-closed", ("door-1",)),
    FactAtom("door-open", "door-open", ("door-1",)),
    FactAtom("cube-on-counter", "on-counter", ("cube-1",)),
    FactAtom("cube-lifted", "lifted", ("cube-1",)),
    FactAtom("cube-in-cabinet", "in-cabinet", ("cube-1",)),
    FactAtom("valve-closed", "valve-closed", ("valve-1",)),
    FactAtom("valve-open", "valve-open", ("valve-1",)),
)
"""The kitchen's world facts (what ``world.world_facts`` returns) and their atoms."""
WORLD_FACTS: tuple[str, ...] = tuple(fact.name for fact in FACT_ATOMS)
"""The kitchen's world fact names (one cube)."""
HAND_EMPTY_FACT = "hand-empty"
"""The fact that the hand holds nothing (the domain's ``hand_empty``)."""
MAX_CUBES = 3
"""The most cubes a kitchen scene holds (its counter square fits them with room for the
fingers between them, ``cubes.CUBE_CLEARANCE``)."""
_ATOM_OF = {fact.name: fact for fact in FACT_ATOMS}
CUBE_FACTS: tuple[str, ...] = tuple(f.name for f in FACT_ATOMS if f.args == ("cube-1",))
"""Cube 1's facts (``holding-cube``, ``cube-on-counter`` ...): what each cube has."""


def cube_name(k: int) -> str:
    """Cube k's PDDL object: ``cube-1``, ``cube-2`` ..."""
    return f"cube-{k}"


def cube_prefix(k: int) -> str:
    """Cube k's world-field prefix and object-frame name: ``cube``, ``cube2``, ``cube3``."""
    return "cube" if k == 1 else f"cube{k}"


def cube_fact(fact: str, k: int) -> str:
    """Cube k's fact of cube 1's ``fact``: the name for cube 1, the atom for another
    (``cube_fact("cube-on-counter", 2)`` is ``(on-counter cube-2)``)."""
    if k == 1:
        return fact
    return atom_text((_ATOM_OF[fact].predicate, cube_name(k)))


def cube_instances(cubes: int) -> tuple[ObjectInstance, ...]:
    """The scene's objects with ``cubes`` cubes: ``INSTANCES``, then ``cube-2`` ...
    (located by the frames ``cube2`` ..., ``cube_prefix``)."""
    first = INSTANCES[0]
    more = (replace(first, name=cube_name(k), frame=cube_prefix(k)) for k in range(2, cubes + 1))
    return INSTANCES[:1] + tuple(more) + INSTANCES[1:]


def world_fact_names(cubes: int) -> tuple[str, ...]:
    """Every world fact with ``cubes`` cubes: ``WORLD_FACTS``, then each further cube's."""
    more = (cube_fact(f, k) for k in range(2, cubes + 1) for f in CUBE_FACTS)
    return WORLD_FACTS + tuple(more)


_CUBE = (("c", "cube"),)
_DOOR = (("d", "door"),)
_VALVE = (("v", "valve"),)
SKILL_PARAMETERS: dict[str, tuple[tuple[str, str], ...]] = {
    **dict.fromkeys(
        (
            "move-home-to-cube",
            "move-cube-to-home",
            "move-cabinet-to-cube",
            "grab-cube",
            "pick-up-cube",
            "move-cube-to-cabinet",
            "place-cube-in-cabinet",
            "release-cube",
        ),
        _CUBE,
    ),
    **dict.fromkeys(
        (
            "move-home-to-door",
            "move-door-to-home",
            "grab-handle",
            "slide-door-open",
            "release-handle",
        ),
        _DOOR,
    ),  # fmt: skip
    **dict.fromkeys(
        (
            "move-home-to-valve",
            "move-valve-to-home",
            "lower-to-valve",
            "push-valve-open",
            "leave-valve",
        ),
        _VALVE,
    ),  # fmt: skip
}
"""Each skill's lifted parameters (``grab-cube(?c - cube)``): the object it acts on. One
policy per skill, learned in its object's frame; the skills between the cabinet and home
act on none."""
