"""Domains by name: registered in process, or announced by installed packages.

A package announces a domain with an entry point in the ``osg_control.domains`` group whose
object is a zero-argument function returning a ``Domain`` (the kitchen's is declared in
``pyproject.toml``); ``register_domain`` adds one at run time (e.g. from a test or a
notebook). Domains are built on first use and cached.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from importlib.metadata import entry_points

from osg_control.domain.base import Domain
from osg_control.errors import DomainError

ENTRY_POINT_GROUP = "osg_control.domains"

_FACTORIES: dict[str, Callable[[], Domain]] = {}
_BUILT: dict[str, Domain] = {}


def register_domain(name: str, factory: Callable[[], Domain]) -> None:
    """Make a domain available under ``name`` (replacing one of the same name)."""
    _FACTORIES[name] = factory
    _BUILT.pop(name, None)


@contextmanager
def domain_override(domain: Domain, name: str | None = None) -> Iterator[Domain]:
    """Within the block, ``get_domain(name)`` (default ``domain.name``; e.g.
    ``kitchen[cube=2]``) gives ``domain`` (e.g. the domain with the robot ``osg --robot``
    chose), in this process and in worker processes forked inside the block; the registry
    is as before after it."""
    key = domain.name if name is None else name
    saved = _BUILT.get(key)
    _BUILT[key] = domain
    try:
        yield domain
    finally:
        if saved is None:
            _BUILT.pop(key, None)
        else:
            _BUILT[key] = saved


def _installed() -> dict[str, Callable[[], Callable[[], Domain]]]:
    """Entry point name -> its loader (which imports the module and gives the factory)."""
    return {point.name: point.load for point in entry_points(group=ENTRY_POINT_GROUP)}


def domain_names() -> list[str]:
    """Every known domain name, sorted."""
    return sorted(set(_FACTORIES) | set(_installed()))


def get_domain(name: str) -> Domain:
    """The domain registered under ``name``, or ``NAME@ROBOT`` (``Domain.ref``): domain
    NAME with the registered robot ROBOT (``Domain.with_robot``), or ``NAME[TYPE=N,...]``:
    domain NAME with N objects of TYPE in its scene (``Domain.with_counts``).

    Raises:
        DomainError: an unknown name (the known ones listed), or a factory that does not
            give a valid ``Domain``.
        RobotDescriptionError: an unknown robot after ``@`` (the known ones listed).
        UnreachableError: a robot that does not reach the domain's nodes.
    """
    if name in _BUILT:
        return _BUILT[name]
    if "@" in name:
        base, robot = name.split("@", 1)
        _BUILT[name] = get_domain(base).with_robot(robot)
        return _BUILT[name]
    if name.endswith("]") and "[" in name:
        base, counts = name[:-1].split("[", 1)
        _BUILT[name] = get_domain(base).with_counts(_counts(name, counts))
        return _BUILT[name]
    factory = _FACTORIES.get(name)
    if factory is None:
        loader = _installed().get(name)
        if loader is None:
            raise DomainError(
                f"unknown domain {name!r}; known domains: {', '.join(domain_names())}"
            )
        factory = loader()
    domain = factory()
    if not isinstance(domain, Domain):
        raise DomainError(f"domain {name!r}: its factory returned {type(domain).__name__}")
    if domain.name != name:
        raise DomainError(f"domain {name!r}: its factory built a domain named {domain.name!r}")
    _BUILT[name] = domain
    return domain


def _counts(ref: str, text: str) -> dict[str, int]:
    """``cube=2,plate=1`` as counts.

    Raises:
        DomainError: naming ``ref`` and what cannot be read.
    """
    counts = {}
    for part in text.split(","):
        kind, _, number = part.partition("=")
        if not kind.strip() or not number.strip().isdigit():
            raise DomainError(f"domain {ref!r}: cannot read object counts {text!r} (TYPE=N,...)")
        counts[kind.strip()] = int(number)
    return counts
