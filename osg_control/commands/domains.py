"""``osg domains``: every registered domain with its skills, facts, tasks and start regions."""

from __future__ import annotations

import argparse
import json

from osg_control.domain.registry import domain_names, get_domain


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``domains`` to the ``osg`` parser."""
    parser = subparsers.add_parser(
        "domains", help="list the registered domains (skills, facts, tasks, start regions)"
    )
    parser.add_argument("--json", action="store_true", help="print the full description as JSON")
    parser.set_defaults(func=run_domains)


def run_domains(args: argparse.Namespace) -> int:
    """Describe every registered domain."""
    summaries = [get_domain(name).summary() for name in domain_names()]
    if args.json:
        print(json.dumps(summaries, indent=2))
        return 0
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
    return 0
