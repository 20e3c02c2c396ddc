"""Validation of env options: a start or a configuration that means nothing is refused.

A NaN start position or scene option would otherwise make MuJoCo reset to its default pose
and the episode run from a world nobody asked for; an unknown option name, a fact the
start world does not have or a NaN noise level would be silently ignored. Each domain's env
declares its data (its facts, ``world`` options, objects it can hold, its configuration's
ranges); the checks here are shared.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from numbers import Real
from typing import Any

import numpy as np

from osg_control.errors import EnvOptionError, lookup


def finite_option(name: str, value: Any, shape: tuple[int, ...] = ()) -> np.ndarray:
    """``value`` as a finite float array of ``shape``, else ``EnvOptionError`` naming it.
    Numbers only: ``True`` (which numpy reads as 1) and numeric strings are refused."""
    message = f"reset option {name} must be finite numbers of shape {shape}, got {value!r}"
    try:
        raw = np.asarray(value)
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise EnvOptionError(message) from None
    if raw.dtype.kind not in "iuf" or array.shape != shape or not np.all(np.isfinite(array)):
        raise EnvOptionError(message)
    return array


def check_env_arguments(owner: str, skill: Any, config: Any, config_type: type) -> None:
    """Refuse an env constructor's ``skill`` that is not a skill spec (or None) and a
    ``config`` that is not a ``config_type`` (or None), naming the argument.

    Raises:
        EnvOptionError: ``owner(skill=5)``, ``owner(config="x")``.
    """
    from osg_control.domain.spec import SkillSpec

    if skill is not None and not isinstance(skill, SkillSpec):
        raise EnvOptionError(f"{owner}: skill must be a skill name or a SkillSpec, got {skill!r}")
    if config is not None and not isinstance(config, config_type):
        raise EnvOptionError(f"{owner}: config must be a {config_type.__name__}, got {config!r}")


def reset_options(options: Any) -> dict[str, Any]:
    """The ``options`` of a reset as a dict (None: none).

    Raises:
        EnvOptionError: anything but a mapping of option names (``"node"``, ``5``).
    """
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise EnvOptionError(
            f"reset options must be a dict of option name -> value, got {options!r}"
        )
    return dict(options)


def node_option(options: Mapping[str, Any], default: str, nodes: Iterable[str]) -> str:
    """The ``node`` reset option (absent or None: ``default``); an empty name is refused
    like any other unknown node, never read as the default.

    Raises:
        EnvOptionError: not one of ``nodes``.
    """
    name = options.get("node")
    return str(choice_option("node", default if name is None else name, tuple(nodes)))


Sphere = tuple[tuple[float, float, float], float]
"""A robot's workspace: centre [m] and radius [m] (``control.robot_model.workspace``)."""


def check_reach(option: str, position: np.ndarray, reach: Sphere) -> None:
    """Refuse the reset option ``option`` at ``position`` (a start, an object) outside the
    robot's workspace ``reach``: the arm would stop short and the episode start from a pose
    nobody asked for.

    Raises:
        EnvOptionError: naming the option, the position, the distance and the reach.
    """
    centre, radius = reach
    distance = float(np.linalg.norm(np.asarray(position) - np.asarray(centre, dtype=float)))
    if distance > radius:
        raise EnvOptionError(
            f"reset option {option} {np.asarray(position).tolist()} is {distance:.3f} m from "
            f"the arm's first joint at {list(centre)}, out of the arm's reach ({radius:.3f} m)"
        )


GRIPPER_STATES = ("open", "closed")
"""The values of the ``gripper`` reset option (every domain's)."""


def check_start_options(centre: Any, radius: Any, angle: Any) -> tuple[np.ndarray, float, float]:
    """The start pose options (``position`` (3,), ``radius``, ``angle``) as numbers.

    Raises:
        EnvOptionError: a non-finite, wrong-shaped or negative one, named with its value.
    """
    sizes = []
    for name, value in (("radius", radius), ("angle", angle)):
        size = float(finite_option(name, value))
        if size < 0:
            raise EnvOptionError(f"reset option {name} must be >= 0, got {value!r}")
        sizes.append(size)
    return finite_option("position", centre, (3,)), sizes[0], sizes[1]


def check_names(given: Iterable[str], known: Iterable[str], what: str) -> None:
    """Refuse a name not among ``known`` (``what``: e.g. ``"reset option"``), naming it and
    listing the known ones.

    Raises:
        EnvOptionError: ``unknown <what> 'x'; known <what>s: a, b``.
    """
    table = dict.fromkeys(known)
    for name in given:
        lookup(table, name, what, EnvOptionError)


def choice_option(name: str, value: Any, choices: Iterable[Any]) -> Any:
    """``value`` if it is one of ``choices``, else ``EnvOptionError`` naming the option."""
    choices = tuple(choices)
    if value not in choices:
        raise EnvOptionError(f"reset option {name} must be one of {choices}, got {value!r}")
    return value


def facts_option(value: Any, known: Iterable[str]) -> frozenset[str]:
    """The ``facts`` reset option as a set of the domain's facts (``known``; empty: not
    declared, any name passes).

    Raises:
        EnvOptionError: not a collection of names, or a fact the domain does not have.
    """
    if isinstance(value, Mapping):
        raise EnvOptionError(
            f"reset option facts must be a collection of the facts that hold (a set or list "
            f"of names), got a dict {value!r}: a fact mapped to False would be taken as "
            "holding"
        )
    if isinstance(value, str) or not isinstance(value, Iterable):
        raise EnvOptionError(f"reset option facts must be a collection of facts, got {value!r}")
    items = list(value)
    if not all(isinstance(item, str) for item in items):
        raise EnvOptionError(f"reset option facts must hold fact names (strings), got {value!r}")
    facts = frozenset(items)
    known = tuple(known)
    if known:
        check_names(sorted(facts, key=str), known, "fact")
    return facts


def check_facts_hold(asked: frozenset[str], holding: frozenset[str], given: str) -> None:
    """Refuse a start whose ``facts`` option does not hold in the world the other options
    (``given``, described for the message) put in place.

    Raises:
        EnvOptionError: naming the facts that do not hold and the facts that do.
    """
    missing = sorted(asked - holding)
    if missing:
        raise EnvOptionError(
            f"reset options contradict each other: facts {missing} do not hold in the start "
            f"world of {given}, whose facts are {sorted(holding)}"
        )


@dataclass(frozen=True)
class Bounds:
    """A configuration field's range: a finite number with ``low <= x <= high`` (``low <
    x`` if ``open_low``); ``integer``: an int; ``optional``: None allowed."""

    low: float = 0.0
    high: float = math.inf
    open_low: bool = False
    integer: bool = False
    optional: bool = False

    def admits(self, value: Any) -> bool:
        """Whether ``value`` lies in the range."""
        if value is None:
            return self.optional
        kind = int if self.integer else Real
        if isinstance(value, bool) or not isinstance(value, kind):
            return False
        number = float(value)
        above = number > self.low if self.open_low else number >= self.low
        return math.isfinite(number) and above and number <= self.high

    def describe(self) -> str:
        """The range in words, for error messages."""
        low = f"{'>' if self.open_low else '>='} {self.low:g}"
        high = "" if self.high == math.inf else f" and <= {self.high:g}"
        kind = "an integer" if self.integer else "a finite number"
        return f"{kind} {low}{high}" + (" or None" if self.optional else "")


def check_fields(config: Any, bounds: Mapping[str, Bounds]) -> None:
    """Refuse a configuration (a dataclass) with a field outside its ``bounds``.

    Raises:
        EnvOptionError: naming the class, the field, its range and its value.
    """
    for name, bound in bounds.items():
        value = getattr(config, name)
        if not bound.admits(value):
            raise EnvOptionError(
                f"{type(config).__name__}.{name} must be {bound.describe()}, got {value!r}"
            )
