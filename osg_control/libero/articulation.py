"""What moves on LIBERO's fixtures, declared once, and the atoms a task file leaves unsaid.

A task file states only what differs from a fixture's rest pose: ``(open X)`` for a drawer
or door that starts open, ``(turnon F)`` for a stove that starts on. The lifted domain
(``operators``) plans over both states, so each problem's init gets the closed-world
complement (``(close X)``, ``(turnoff F)``) and the static links ``(door-of X R)`` (the
openable ``X`` whose state gives the hand access to region ``R``), from the table below.

The table is LIBERO's assets as its predicates read them (``envs/objects/
articulated_objects.py``; a region of a cabinet is a drawer when its site sits on a body
with a joint, ``object_sites_dict[...].joints``): a cabinet's ``top_region``,
``middle_region`` and ``bottom_region`` are drawers (its ``top_side`` is a surface); the
microwave's door gives access to its ``heating_region``; a stove's knob turns it on.
"""

from __future__ import annotations

from osg_control.libero.problem import Atom, LiberoProblem, TaskFileError

DRAWER_REGIONS: dict[str, tuple[str, ...]] = {
    cabinet: ("top_region", "middle_region", "bottom_region")
    for cabinet in ("wooden_cabinet", "white_cabinet", "yellow_cabinet")
}
"""Fixture type -> its regions that are drawers (each opens and closes itself)."""
DOOR_REGIONS: dict[str, tuple[str, ...]] = {"microwave": ("heating_region",)}
"""Fixture type -> the regions behind its door (the fixture itself opens and closes)."""
KNOB_FIXTURES: tuple[str, ...] = ("flat_stove", "yellow_stove")
"""Fixture types a knob turns on and off."""


def _region_suffix(problem: LiberoProblem, region: str) -> str:
    """``basket_1_contain_region`` -> ``contain_region`` (the name less its parent's)."""
    return region[len(problem.regions[region].parent) + 1 :]


def doors(problem: LiberoProblem) -> dict[str, tuple[str, ...]]:
    """Each openable thing of the task (a drawer region or a door fixture) -> the regions
    its state gives access to."""
    found: dict[str, tuple[str, ...]] = {}
    for name in problem.regions:
        parent = problem.regions[name].parent
        kind = problem.fixtures.get(parent, "")
        if _region_suffix(problem, name) in DRAWER_REGIONS.get(kind, ()):
            found[name] = (name,)
    for fixture, kind in problem.fixtures.items():
        behind = DOOR_REGIONS.get(kind, ())
        regions = tuple(
            r for r in problem.regions
            if problem.regions[r].parent == fixture and _region_suffix(problem, r) in behind
        )  # fmt: skip
        if regions:
            found[fixture] = regions
    return found


def knobs(problem: LiberoProblem) -> tuple[str, ...]:
    """The task's fixtures a knob turns on and off."""
    return tuple(f for f, kind in problem.fixtures.items() if kind in KNOB_FIXTURES)


def implied_init(problem: LiberoProblem) -> tuple[Atom, ...]:
    """The init atoms the file leaves unsaid: ``(close X)`` / ``(turnoff F)`` for each
    openable / knob not stated open / on, ``(door-of X R)``, and ``(accessible R)`` for
    every region not behind a closed door or drawer.

    Raises:
        TaskFileError: the file's init opens or turns on something the table above does
            not articulate (the table would be incomplete); the message names the atom.
    """
    gates, turnable = doors(problem), knobs(problem)
    stated = {(a.predicate, a.args[0]) for a in problem.init if len(a.args) == 1}
    for predicate, thing in sorted(stated):
        if (predicate == "open" and thing not in gates) or (
            predicate == "turnon" and thing not in turnable
        ):
            raise TaskFileError(
                f"{problem.path}: init ({predicate} {thing}) names something no declared "
                "drawer, door or knob moves (libero/articulation.py)"
            )
    atoms: list[Atom] = []
    shut: set[str] = set()
    for thing, regions in gates.items():
        is_open = ("open", thing) in stated
        atoms += [Atom("door-of", (thing, r)) for r in regions]
        if not is_open:
            atoms.append(Atom("close", (thing,)))
            shut.update(regions)
    atoms += [Atom("accessible", (r,)) for r in problem.regions if r not in shut]
    atoms += [Atom("turnoff", (f,)) for f in turnable if ("turnon", f) not in stated]
    return tuple(atoms)
