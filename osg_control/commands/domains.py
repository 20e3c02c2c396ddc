"""``osg domains``: every registered domain with its skills, facts, tasks and start regions."""

from __future__ import annotations

import argparse

from osg_control.domain.registry import domain_names, get_domain
from osg_control.errors import DomainError
from osg_control.json_files import dump_json


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``domains`` to the ``osg`` parser."""
    parser = subparsers.add_parser(
        "domains", help="list the registered domains (skills, facts, tasks, start regions)"
    )
    parser.add_argument("--json", action="store_true", help="print the full description as JSON")
    parser.set_defaults(func=run_domains)


def run_domains(args: argparse.Namespace) -> int:
    """Describe every registered domain; one that cannot be built is listed with its error
    (exit 1) and the others still are."""
    summaries, broken = [], []
    for name in domain_names():
        try:
            summaries.append(get_domain(name).summary())
        except DomainError as err:
            broken.append({"name": name, "error": str(err)})
    if args.json:
        print(dump_json(summaries + broken))
        return 1 if broken else 0
    for entry in broken:
        print(f"{entry['name']}: BROKEN: {entry['error']}")
    for s in summaries:
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
    return 1 if broken else 0
