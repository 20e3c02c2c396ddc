"""``osg domains``: every registered domain with its skills, facts, tasks and start regions."""

from __future__ import annotations

import argparse
from typing import Any

from osg_control.commands.listing import add_listing_verb
from osg_control.domain.registry import domain_names, get_domain


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``domains [--json]`` to the ``osg`` parser: every registered domain described;
    one that cannot be built is listed with its error (exit 1) and the others still are."""
    add_listing_verb(
        subparsers,
        "domains",
        "list the registered domains (skills, facts, tasks, start regions)",
        domain_names,
        lambda name: get_domain(name).summary(),
        _print_domain,
    )


def _print_domain(s: dict[str, Any]) -> None:
    print(f"{s['name']}: {s['description']}")
    print(f"  nodes ({len(s['nodes'])}): {', '.join(s['nodes'])}")
    print(f"  facts ({len(s['facts'])}): {', '.join(s['facts'])}")
    print(f"  skills ({len(s['skills'])}):")
    for skill in s["skills"]:
        print(f"    {skill['name']:26s} {skill['kind']:9s} {skill['start']} -> {skill['end']}")
    print(f"  tasks ({len(s['tasks'])}):")
    for task in s["tasks"]:
        print(f"    {task['name']:22s} goal {' '.join(task['goal'])}")
    print(
        f"  start regions ({len(s['start_regions'])}): "
        + ", ".join(r["name"] for r in s["start_regions"])
    )
