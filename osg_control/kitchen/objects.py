"""The kitchen's objects and facts as typed PDDL: types, instances, predicates, and each
world fact's ground atom (declared once here; ``skills.WORLD_FACTS`` is derived)."""

from __future__ import annotations

from osg_control.domain.lifted import FactAtom, ObjectInstance, PredicateDecl

TYPES: dict[str, str] = {"cube": "object", "door": "object", "handle": "object", "valve": "object"}
"""Object types, each a direct subtype of ``object``."""
INSTANCES: tuple[ObjectInstance, ...] = (
    ObjectInstance("cube-1", "cube", frame="cube"),
    ObjectInstance("door-1", "door", frame="door"),
    ObjectInstance("handle-1", "handle"),
    ObjectInstance("valve-1", "valve"),
)
"""The scene's objects: one cube (located by the ``CUBE`` frame, which its nodes are
anchored to), the cabinet's sliding door (the ``DOOR`` frame: its travel, which the
``handle`` node follows), its handle and the valve."""
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
"""The kitchen's world fact names."""

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
