"""``osg datasets minari`` and ``osg datasets import``: data sets out to and in from Minari
(and, with ``--layout lerobot``, in from a LeRobot data set)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from osg_control.commands import domain_of
from osg_control.data.datasets import dataset_summary
from osg_control.json_files import dump_json


def add_verbs(verbs: argparse._SubParsersAction) -> None:
    """Add ``minari`` and ``lerobot`` (exports) and ``import`` to the ``osg datasets`` verbs."""
    lerobot = verbs.add_parser(
        "lerobot",
        help="write a data set file (or a folder of them) as a LeRobot v3.0 data set",
        description="Parquet data and meta files of LeRobot's v3.0 layout, written with "
        "pyarrow: observation.state, action, next.reward, next.done, next.truncated, "
        "next.observation.state, next.world_state, frame and episode indices, timestamps at "
        "the domain's control rate, each skill a task; meta/info.json, stats.json, "
        "tasks.parquet and episodes/. Read it with lerobot's LeRobotDataset.",
    )
    lerobot.add_argument("path", type=Path, help="a data set file (<skill>.h5) or a folder of them")
    lerobot.add_argument(
        "--out",
        type=Path,
        help="the data set folder to write (default: <path without .h5>-lerobot)",
    )
    lerobot.add_argument("--force", action="store_true", help="replace an existing folder")
    lerobot.add_argument("--json", action="store_true")
    lerobot.set_defaults(func=run_lerobot)

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
        help="turn a Minari (or LeRobot) data set into data set files: one skill's, or (D4RL "
        "kitchen layout, franka-kitchen) one per skill",
        description="The project layout needs 10-D Box observations and 7-D Box actions and "
        "writes one skill's file (--skill, --out FILE). The lerobot layout reads a LeRobot "
        "v3.0 data set folder (as `osg datasets lerobot` writes it) and writes the episodes "
        "of task --skill to --out FILE. The D4RL kitchen layout (a Dict "
        "observation space with 'observation' and 'achieved_goal', 9-D joint actions: "
        "D4RL/kitchen/complete-v2, mixed-v2, partial-v2) needs --domain franka-kitchen and "
        "writes <OUT>/<skill>.h5 per skill, segmenting each episode at its task completions.",
    )
    imported.add_argument(
        "source", help="a Minari data set folder or its id under the root; a LeRobot folder"
    )
    imported.add_argument("--skill", help="the skill the data is for (project layout only)")
    imported.add_argument(
        "--out",
        type=Path,
        required=True,
        help="file to write (<skill>.h5); with the D4RL layout the folder for the files",
    )
    imported.add_argument(
        "--layout",
        default="auto",
        help="the source's layout: project (a Minari data set of this package's states and "
        "actions), lerobot (a LeRobot v3.0 folder), one of the domain's outside layouts "
        "(franka-kitchen: d4rl), or auto (default: lerobot for a folder with meta/info.json, "
        "else the domain's layout that recognises the source, else project)",
    )
    imported.add_argument(
        "--success",
        choices=["rewards", "predicate"],
        default=None,
        help="project layout: success steps from positive rewards (default) or from the "
        "skill's predicate over the recorded states (needs infos/world_states)",
    )
    imported.add_argument("--json", action="store_true")
    imported.set_defaults(func=run_import)


def run_export(args: argparse.Namespace) -> int:
    """Export and print where the data set went."""
    from osg_control.data.minari_export import export_minari

    target = export_minari(args.path, args.id, domain_of(args), args.out, args.force)
    if args.json:
        print(dump_json({"id": args.id, "path": str(target)}, indent=None))
    else:
        print(f"Minari data set {args.id} written to {target}")
    return 0


def run_lerobot(args: argparse.Namespace) -> int:
    """Export to LeRobot and print where the data set went."""
    from osg_control.data.lerobot_export import export_lerobot

    out = args.out or args.path.with_name(f"{args.path.stem}-lerobot")
    domain = domain_of(args)
    target = export_lerobot(args.path, out, domain, args.force)
    fps = domain.control_hz
    if args.json:
        print(dump_json({"path": str(target), "fps": fps}))
    else:
        print(f"LeRobot v3.0 data set written to {target} ({fps:g} frames per second)")
    return 0


def _refuse_out_in_source(source: str, out: Path) -> None:
    """Refuse an ``--out`` that is the source data set or lies inside it (the import
    would overwrite what it reads).

    Raises:
        UsageError: naming both paths.
    """
    from osg_control.data.minari_import import minari_root
    from osg_control.errors import UsageError

    target = Path(out).expanduser().resolve()
    for candidate in (Path(source).expanduser(), minari_root() / str(source)):
        if candidate.exists():
            place = candidate.resolve()
            if target == place or place in target.parents:
                raise UsageError(
                    f"--out {out} is inside the source data set {source}: the import would "
                    "overwrite what it reads; write it elsewhere"
                )


def run_import(args: argparse.Namespace) -> int:
    """Import and print the new data set's summary (an outside layout: its importer's)."""
    from osg_control.data.lerobot_import import is_lerobot
    from osg_control.errors import UsageError

    domain = domain_of(args)
    _refuse_out_in_source(args.source, args.out)
    layouts = {layout.name: layout for layout in domain.dataset_layouts}
    name = args.layout
    if name == "auto":
        found = [layout.name for layout in domain.dataset_layouts if layout.detects(args.source)]
        name = "lerobot" if is_lerobot(args.source) else found[0] if found else "project"
    if name == "lerobot":
        return _import_lerobot(args)
    if name != "project":
        if name not in layouts:
            raise UsageError(
                f"domain {domain.name!r} imports no {name!r} layout (its layouts: project, lerobot"
                + "".join(f", {known}" for known in layouts)
                + ")"
            )
        if args.skill or args.success:
            raise UsageError(
                f"--skill and --success apply to the project layout; the {name} layout "
                "writes every skill its episodes hold, with its own successes"
            )
        summary = layouts[name].imports(domain, args.source, args.out)
        if args.json:
            print(dump_json(summary.to_json()))
        else:
            print("\n".join(summary.lines()))
        return 0
    if not args.skill:
        raise UsageError("--skill is required for a project-layout Minari data set")
    from osg_control.data.minari_import import import_minari

    imported = dataset_summary(
        import_minari(domain, args.source, args.skill, args.out, args.success or "rewards")
    )
    return _print_import(imported, args.json)


def _import_lerobot(args: argparse.Namespace) -> int:
    """Import the episodes of task ``--skill`` from a LeRobot folder."""
    from osg_control.data.lerobot_import import import_lerobot
    from osg_control.errors import UsageError

    if not args.skill:
        raise UsageError("--skill is required for a LeRobot data set (the task to import)")
    if args.success not in (None, "rewards"):
        raise UsageError("--success predicate applies to Minari data sets; LeRobot's is rewards")
    imported = dataset_summary(import_lerobot(domain_of(args), args.source, args.skill, args.out))
    return _print_import(imported, args.json)


def _print_import(imported: dict[str, Any], as_json: bool) -> int:
    """Print an imported data set's summary."""
    if as_json:
        print(dump_json(imported))
    else:
        print(
            f"{imported['path']}: skill {imported['skill']}, {imported['episodes']} episodes, "
            f"success rate {imported['success_rate']:.2f}"
        )
    return 0
