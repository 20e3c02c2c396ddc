"""Sub-commands of ``osg``; each module defines ``register(subparsers)``.

A module's ``register`` adds its parser and sets ``func`` (called with the parsed args,
returning the exit code). Add a module here to expose it.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from osg_control.domain.base import Domain

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
)


def domain_of(args: argparse.Namespace) -> Domain:
    """The domain ``osg --domain NAME`` selected (the registry's default without it)."""
    from osg_control.domain.registry import get_domain

    return get_domain(args.domain)


def add_filter_argument(parser: argparse.ArgumentParser) -> None:
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
