"""``osg datasets minari`` and ``osg datasets import``: data sets out to and in from Minari."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from osg_control.commands import domain_of
from osg_control.data.datasets import dataset_summary


def add_verbs(verbs: argparse._SubParsersAction) -> None:
    """Add ``minari`` (export) and ``import`` to the ``osg datasets`` verbs."""
    export = verbs.add_parser(
        "minari",
        help="write a data set file as a Minari data set",
        description="One group per episode, T+1 observations, world states under infos, "
        "metadata.json with the spaces and the env spec; read it with "
        "minari.load_dataset(ID) when MINARI_DATASETS_PATH is --out.",
    )
    export.add_argument("path", type=Path, help="a project data set file (<skill>.h5)")
    export.add_argument("--id", required=True, help="Minari id NAMESPACE/NAME-vN")
    export.add_argument(
        "--out",
        type=Path,
        help="Minari data-sets folder (default: $MINARI_DATASETS_PATH or ~/.minari/datasets)",
    )
    export.add_argument("--force", action="store_true", help="replace an existing data set")
    export.add_argument("--json", action="store_true")
    export.set_defaults(func=run_export)

    imported = verbs.add_parser(
        "import",
        help="turn a Minari data set into a data set file for one skill",
        description="The Minari data set needs 10-D Box observations and 7-D Box actions.",
    )
    imported.add_argument("source", help="a Minari data set folder, or its id under the root")
    imported.add_argument("--skill", required=True, help="the skill the data is for")
    imported.add_argument("--out", type=Path, required=True, help="file to write (<skill>.h5)")
    imported.add_argument(
        "--success",
        choices=["rewards", "predicate"],
        default="rewards",
        help="success steps from positive rewards (default) or from the skill's predicate "
        "over the recorded states (needs infos/world_states)",
    )
    imported.add_argument("--json", action="store_true")
    imported.set_defaults(func=run_import)


def run_export(args: argparse.Namespace) -> int:
    """Export and print where the data set went."""
    from osg_control.data.minari_export import export_minari

    target = export_minari(args.path, args.id, args.out, args.force, domain_of(args).env_id)
    if args.json:
        print(json.dumps({"id": args.id, "path": str(target)}))
    else:
        print(f"Minari data set {args.id} written to {target}")
    return 0


def run_import(args: argparse.Namespace) -> int:
    """Import and print the new data set's summary."""
    from osg_control.data.minari_import import import_minari

    summary = dataset_summary(
        import_minari(domain_of(args), args.source, args.skill, args.out, args.success)
    )
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(
            f"{summary['path']}: skill {summary['skill']}, {summary['episodes']} episodes, "
            f"success rate {summary['success_rate']:.2f}"
        )
    return 0
