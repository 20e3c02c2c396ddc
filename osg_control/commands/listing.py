"""The listing verbs' shared loop (``osg domains``, ``osg robots``): every registered name
described, one that cannot be loaded listed with its error (exit 1) and the others still."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterable
from typing import Any

from osg_control.errors import OSGError
from osg_control.json_files import dump_json


def print_registered(
    names: Iterable[str],
    describe: Callable[[str], dict[str, Any]],
    as_json: bool,
    print_entry: Callable[[dict[str, Any]], None],
) -> int:
    """Describe each of ``names`` (``describe``), as JSON or with ``print_entry``.

    Returns:
        The exit code: 1 if any could not be described (an ``OSGError``), else 0.
    """
    summaries, broken = [], []
    for name in names:
        try:
            summaries.append(describe(name))
        except OSGError as err:
            broken.append({"name": name, "error": str(err)})
    if as_json:
        print(dump_json(summaries + broken))
        return 1 if broken else 0
    for entry in broken:
        print(f"{entry['name']}: BROKEN: {entry['error']}")
    for summary in summaries:
        print_entry(summary)
    return 1 if broken else 0


def add_listing_verb(
    subparsers: argparse._SubParsersAction,
    verb: str,
    help_text: str,
    names: Callable[[], Iterable[str]],
    describe: Callable[[str], dict[str, Any]],
    print_entry: Callable[[dict[str, Any]], None],
) -> None:
    """Add ``verb [--json]`` listing every registered name (``print_registered``)."""
    parser = subparsers.add_parser(verb, help=help_text)
    parser.add_argument("--json", action="store_true", help="print the descriptions as JSON")
    parser.set_defaults(
        func=lambda args: print_registered(names(), describe, args.json, print_entry)
    )
