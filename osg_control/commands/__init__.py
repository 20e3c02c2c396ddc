"""Sub-commands of ``osg``; each module defines ``register(subparsers)``.

A module's ``register`` adds its parser and sets ``func`` (called with the parsed args,
returning the exit code). Add a module here to expose it.
"""

from __future__ import annotations

import argparse
from types import ModuleType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from osg_control.domain.base import Domain
    from osg_control.perception.spec import PerceptionSpec

DEFAULT_DOMAIN = "kitchen"
"""The domain ``osg`` uses without ``--domain``: the first one this package ships."""

COMMAND_MODULES: tuple[str, ...] = (
    "collect",
    "run",
    "evaluate",
    "classifier",
    "train",
    "graph",
    "pddl",
    "plan",
    "reproduce",
    "domains",
    "robots",
)


DOMAIN_VERBS_GROUP = "osg_control.domain_verbs"
"""Entry points of domains that bring their own verbs instead of the core's: the name is the
domain's (``osg --domain NAME``), the object a module with ``register(subparsers)``, as a
command module. For a domain that is not (yet) a ``Domain`` (e.g. an outside benchmark whose
skills are not shipped yet); ``register_domain_verbs`` adds one at run time."""

_DOMAIN_VERBS: dict[str, str] = {}


def register_domain_verbs(name: str, module: str) -> None:
    """Make ``osg --domain NAME`` use the verbs of ``module`` (imported when used)."""
    _DOMAIN_VERBS[name] = module


def domain_verbs(name: str) -> ModuleType | None:
    """The verbs module of a domain that brings its own (``DOMAIN_VERBS_GROUP``), else None.
    The module is imported only when its domain is selected."""
    import importlib
    from importlib.metadata import entry_points

    module = _DOMAIN_VERBS.get(name)
    if module is None:
        points = {p.name: p.value for p in entry_points(group=DOMAIN_VERBS_GROUP)}
        module = points.get(name)
    return None if module is None else importlib.import_module(module)


def domain_verb_names() -> list[str]:
    """The domains that bring their own verbs, sorted."""
    from importlib.metadata import entry_points

    return sorted({*_DOMAIN_VERBS, *(p.name for p in entry_points(group=DOMAIN_VERBS_GROUP))})


def domain_of(args: argparse.Namespace) -> Domain:
    """The domain ``osg --domain NAME`` selected (the registry's default without it)."""
    from osg_control.domain.registry import get_domain

    return get_domain(args.domain)


def add_filter_argument(parser: argparse._ActionsContainer) -> None:
    """Add ``--filter [GAIN]``: run the policies on filtered TCP estimates (see
    ``osg_control.control.estimator``); absent means raw observations, the paper's protocol."""
    from osg_control.control.estimator import DEFAULT_GAIN

    parser.add_argument(
        "--filter",
        type=float,
        nargs="?",
        const=DEFAULT_GAIN,
        default=None,
        metavar="GAIN",
        help=f"feed the policies a filtered TCP position (gain in (0, 1], default "
        f"{DEFAULT_GAIN} when the flag is given without a value); off by default",
    )


def add_perception_arguments(parser: argparse._ActionsContainer) -> None:
    """Add ``--perception NAME`` and ``--object-noise SIGMA`` (``perception.spec``)."""
    from osg_control.perception.spec import OBJECT_NOISE, PERCEPTIONS

    parser.add_argument(
        "--perception",
        default=None,
        metavar="NAME",
        help=f"what the robot perceives: {', '.join(PERCEPTIONS)} (default: the domain's first, "
        "e.g. the kitchen's paper protocol)",
    )
    parser.add_argument(
        "--object-noise",
        type=float,
        default=None,
        metavar="SIGMA",
        help=f"the robot perception's object-pose noise [m] (default {OBJECT_NOISE})",
    )


def add_randomize_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--randomize-objects``: place the domain's objects uniformly in their placement
    regions (seeded per episode) instead of where the scene has them."""
    parser.add_argument(
        "--randomize-objects",
        action="store_true",
        help="place the domain's objects (the kitchen's cube) uniformly in their placement "
        "regions, seeded per episode (default: where the scene has them)",
    )


def perception_of(
    args: argparse.Namespace, domain: Domain, default_noise: float = 0.0
) -> PerceptionSpec:
    """The perception the command line asks for, with the paper's TCP noise ``--noise``
    (default ``default_noise`` under the paper's protocol, none under the others).

    Raises:
        UsageError: an unknown name, a bad noise level, or a perception the domain does not
            support (exit 2, nothing run).
    """
    from osg_control.perception.spec import check_supported, perception_spec

    name = domain.perceptions[0] if args.perception is None else args.perception
    noise = getattr(args, "noise", None)
    if isinstance(noise, list):
        noise = None  # a list of Table I columns, checked level by level by the verb
    if noise is None:
        noise = default_noise if name == "paper" else 0.0
    spec = perception_spec(name, noise, args.object_noise)
    check_supported(spec, domain.perceptions, domain.name)
    return spec


def camera_setups(domain: Domain, perception: PerceptionSpec) -> list[dict[str, Any]] | None:
    """The ``camera`` perception's cameras (name, resolution, field of view, pose) for a
    command's ``--json``; None under any other perception."""
    if perception.name != "camera":
        return None
    from osg_control.execution.executor import task_env_config

    env = domain.make_env(config=task_env_config(perception))
    try:
        env.reset(seed=0)
        return [setup.to_dict() for setup in env.cameras.rig.setups]
    finally:
        env.close()


def add_backend_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--backend {local,ray}`` and ``--address ADDR`` (see ``osg_control.parallel``)."""
    from osg_control.parallel import BACKENDS

    parser.add_argument(
        "--backend",
        choices=list(BACKENDS),
        default="local",
        help="where the episodes run: " + "; ".join(f"{k}: {v}" for k, v in BACKENDS.items()),
    )
    parser.add_argument(
        "--address",
        default=None,
        metavar="ADDR",
        help="Ray cluster address (host:port from 'ray start --head', ray://host:port or "
        "'auto'); without it --backend ray starts a local Ray instance of --workers CPUs",
    )
