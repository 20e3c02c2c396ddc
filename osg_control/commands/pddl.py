"""``osg pddl export``: write the kitchen domain and the paper's task problems as PDDL."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TypeAlias

from osg_control.planning.graph import load_graph
from osg_control.planning.pddl_io import export_kitchen

Verbs: TypeAlias = "argparse._SubParsersAction[argparse.ArgumentParser]"


def run_export(args: argparse.Namespace) -> int:
    """Write ``osg-kitchen.pddl`` and ``problems/<task>.pddl`` under ``--out``.

    Args:
        args: parsed ``osg pddl export`` arguments.

    Returns:
        0.
    """
    graph = load_graph(args.graph) if args.graph else None
    for path in export_kitchen(args.out, graph):
        print(f"wrote {path}")
    return 0


def register(subparsers: Verbs) -> None:
    """Add ``osg pddl`` and its ``export`` verb."""
    parser = subparsers.add_parser("pddl", help="export the skill graph as PDDL")
    verbs = parser.add_subparsers(dest="pddl_command", metavar="VERB", required=True)
    export = verbs.add_parser(
        "export",
        help="write the domain and the kitchen tasks' problems",
        description="Write the osg-kitchen domain (one operator per skill, costs from "
        "success rates) and one problem per kitchen task of the paper.",
    )
    export.add_argument(
        "--out", type=Path, default=Path("domains"), help="output folder (default: ./domains)"
    )
    export.add_argument(
        "--graph",
        type=Path,
        help="skill graph JSON from `osg graph --out` (default: the skill specs, default costs)",
    )
    export.set_defaults(func=run_export)
