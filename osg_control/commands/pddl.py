"""``osg pddl export``: write a domain's skill graph and its tasks' problems as PDDL."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TypeAlias

from osg_control.commands import domain_of
from osg_control.execution.bundle import measured_graph
from osg_control.planning.graph import load_graph
from osg_control.planning.pddl_io import export_pddl

Verbs: TypeAlias = "argparse._SubParsersAction[argparse.ArgumentParser]"


def run_export(args: argparse.Namespace) -> int:
    """Write ``osg-DOMAIN.pddl`` and ``problems/<task>.pddl`` under ``--out``.

    Args:
        args: parsed ``osg pddl export`` arguments.

    Returns:
        0.
    """
    domain = domain_of(args)
    graph = load_graph(args.graph) if args.graph else measured_graph(domain)
    for path in export_pddl(domain, args.out or Path("domains") / domain.name, graph):
        print(f"wrote {path}")
    return 0


def register(subparsers: Verbs) -> None:
    """Add ``osg pddl`` and its ``export`` verb."""
    parser = subparsers.add_parser("pddl", help="export the skill graph as PDDL")
    verbs = parser.add_subparsers(dest="pddl_command", metavar="VERB", required=True)
    export = verbs.add_parser(
        "export",
        help="write the domain and its tasks' problems",
        description="Write the osg-DOMAIN PDDL domain (one operator per skill, costs "
        "round(-ln p * 1000) of the measured success rates) and one problem per task.",
    )
    export.add_argument(
        "--out", type=Path, default=None, help="output folder (default: ./domains/DOMAIN)"
    )
    export.add_argument(
        "--graph",
        type=Path,
        help="skill graph JSON from `osg graph --out` (default: the domain's specs with the "
        "shipped defaults' measured success rates)",
    )
    export.set_defaults(func=run_export)
