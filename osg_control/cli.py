"""The ``osg`` command: one sub-command per verb, each in ``osg_control.commands``."""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from osg_control import __version__
from osg_control.commands import COMMAND_MODULES
from osg_control.domain.registry import DEFAULT_DOMAIN
from osg_control.errors import OSGError


def build_parser() -> argparse.ArgumentParser:
    """Assemble the parser from every registered command module."""
    parser = argparse.ArgumentParser(
        prog="osg",
        description="Offline Skill Graph robot control: collect, train, plan, run.",
    )
    parser.add_argument("--version", action="version", version=f"osg-control {__version__}")
    parser.add_argument(
        "--domain",
        default=DEFAULT_DOMAIN,
        help=f"the domain to work in (default: {DEFAULT_DOMAIN}; `osg domains` lists them)",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module_name in COMMAND_MODULES:
        importlib.import_module(f"osg_control.commands.{module_name}").register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the process exit code (2 for usage, 1 for an osg-control error)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    try:
        return int(args.func(args) or 0)
    except OSGError as err:
        print(f"osg: error: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("osg: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
