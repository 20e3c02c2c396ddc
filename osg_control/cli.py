"""The ``osg`` command: one sub-command per verb, each in ``osg_control.commands``."""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence

from osg_control import __version__
from osg_control.commands import COMMAND_MODULES
from osg_control.commands.checks import check_args
from osg_control.commands.errors import handle_errors


def build_parser() -> argparse.ArgumentParser:
    """Assemble the parser from every registered command module."""
    parser = argparse.ArgumentParser(
        prog="osg",
        description="Offline Skill Graph robot control: collect, train, plan, run.",
    )
    parser.add_argument("--version", action="version", version=f"osg-control {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module_name in COMMAND_MODULES:
        importlib.import_module(f"osg_control.commands.{module_name}").register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the process exit code (``errors.EXIT_CODES``: 0 success, 1 an
    osg-control error, 2 a bad command-line value, 3 no plan, 130 interrupted)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    with handle_errors(debug=args.debug or bool(os.environ.get("OSG_DEBUG"))) as outcome:
        check_args(args)
        outcome.code = int(args.func(args) or 0)
    return outcome.code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
