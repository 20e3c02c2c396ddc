"""A LIBERO task file (BDDL) as a typed problem: objects and fixtures with their types,
regions, and the init and goal atoms, read by LIBERO's own parser
(``bddl_utils.robosuite_parse_problem``).

LIBERO's goals are a flat conjunction of atoms over movable objects, fixtures and regions
(a region is named ``<parent>_<region>``, e.g. ``basket_1_contain_region``); this module
keeps them as data, and ``pddl_export`` writes them as PDDL problems.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from osg_control.errors import OSGError
from osg_control.libero.extra import require_libero


class TaskFileError(OSGError):
    """A task file LIBERO's parser refuses or whose content is not a LIBERO problem; the
    message names the file."""


@dataclass(frozen=True)
class Atom:
    """A ground atom of a task file: ``(predicate arg ...)``, names as the file spells them
    (lower case)."""

    predicate: str
    args: tuple[str, ...]

    def __str__(self) -> str:
        return f"({' '.join((self.predicate, *self.args))})"


@dataclass(frozen=True)
class Region:
    """A named region of a task file.

    Attributes:
        name: ``<parent>_<region>``, e.g. ``basket_1_contain_region``.
        parent: the object or fixture it lies on or in (the file's ``:target``).
        ranges: its boxes ``(x_min, y_min, x_max, y_max)`` [m] in the parent's frame.
    """

    name: str
    parent: str
    ranges: tuple[tuple[float, ...], ...]


@dataclass(frozen=True)
class LiberoProblem:
    """One task of a suite, as its task file states it.

    Attributes:
        suite: the suite (e.g. ``libero_10_swap``).
        index: the task's index in the suite.
        name: the task's name (its file's stem).
        language: the instruction (not used to decide anything here).
        scene: LIBERO's problem class (e.g. ``libero_kitchen_tabletop_manipulation``).
        objects: movable object -> its type.
        fixtures: fixture -> its type.
        regions: region name -> region.
        init: the atoms that hold at the start.
        goal: the atoms whose conjunction is the task's success (``check_success``).
        path: the task file.
    """

    suite: str
    index: int
    name: str
    language: str
    scene: str
    objects: Mapping[str, str]
    fixtures: Mapping[str, str]
    regions: Mapping[str, Region]
    init: tuple[Atom, ...]
    goal: tuple[Atom, ...]
    path: Path

    def predicates(self) -> frozenset[str]:
        """Every predicate its init and goal use."""
        return frozenset(a.predicate for a in (*self.init, *self.goal))


def _typed(groups: Mapping[str, Any], what: str, path: Path) -> dict[str, str]:
    """``{type: [name, ...]}`` -> ``{name: type}``, a name of two types refused."""
    typed: dict[str, str] = {}
    for type_name, names in groups.items():
        for name in names:
            if typed.setdefault(str(name), str(type_name)) != type_name:
                raise TaskFileError(f"{path}: {what} {name!r} is of two types")
    return typed


def _atoms(raw: Any, path: Path, where: str) -> tuple[Atom, ...]:
    atoms = []
    for item in raw:
        if not item or not all(isinstance(word, str) for word in item):
            raise TaskFileError(f"{path}: {where} holds a malformed atom {item!r}")
        atoms.append(Atom(item[0].lower(), tuple(w.lower() for w in item[1:])))
    return tuple(atoms)


def read_problem(path: str | Path, suite: str = "", index: int = -1) -> LiberoProblem:
    """Parse one task file with LIBERO's parser into a ``LiberoProblem``.

    Raises:
        TaskFileError: the parser refuses the file, or an atom names something the file
            does not declare; the message names the file.
        MissingExtraError: the ``libero`` extra is not installed.
    """
    bddl_utils = require_libero("libero.libero.envs.bddl_utils")
    path = Path(path)
    try:
        parsed = bddl_utils.robosuite_parse_problem(str(path))
    except Exception as err:  # LIBERO's parser raises bare Exceptions and KeyErrors
        raise TaskFileError(f"{path}: LIBERO's parser refused it: {err!r}") from None
    objects = _typed(parsed["objects"], "object", path)
    fixtures = _typed(parsed["fixtures"], "fixture", path)
    regions = {
        name: Region(name, str(r["target"]), tuple(tuple(map(float, b)) for b in r["ranges"]))
        for name, r in parsed["regions"].items()
    }
    problem = LiberoProblem(
        suite=suite,
        index=index,
        name=path.stem,
        language=" ".join(parsed["language_instruction"]),
        scene=str(parsed["problem_name"]),
        objects=objects,
        fixtures=fixtures,
        regions=regions,
        init=_atoms(parsed["initial_state"], path, "init"),
        goal=_atoms(parsed["goal_state"], path, "goal"),
        path=path,
    )
    declared = {*objects, *fixtures, *regions}
    for atom in (*problem.init, *problem.goal):
        unknown = [a for a in atom.args if a not in declared]
        if unknown:
            raise TaskFileError(f"{path}: atom {atom} names undeclared {unknown}")
    if not problem.goal:
        raise TaskFileError(f"{path}: the goal is empty")
    return problem
