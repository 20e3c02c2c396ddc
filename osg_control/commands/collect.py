"""``osg collect`` and ``osg datasets``: scripted data collection, summaries, Minari in/out."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from osg_control.commands import add_backend_arguments, domain_of
from osg_control.commands.minari import add_verbs as add_minari_verbs
from osg_control.data.collect import DEFAULT_EPISODES, collect_skill
from osg_control.data.datasets import (
    dataset_summary,
    load_dataset,
)
from osg_control.errors import DatasetError
from osg_control.io_safety import check_output_dir
from osg_control.json_files import dump_json
from osg_control.parallel import open_executor
from osg_control.paths import cache_dir
from osg_control.pipeline.collect import collection_bytes, skill_episodes


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``collect`` and ``datasets`` to the ``osg`` parser."""
    collect = subparsers.add_parser(
        "collect", help="record scripted noisy episodes (Algorithm 1), one HDF5 file per skill"
    )
    collect.add_argument("--skill", default="all", help="a skill name, or 'all' (default)")
    collect.add_argument(
        "--episodes", type=int, default=None,
        help=f"episodes per skill (default: {DEFAULT_EPISODES}, times the skill's training "
        "recipe's factor: grab-cube collects twice as many)",
    )  # fmt: skip
    collect.add_argument("--workers", type=int, default=2)
    add_backend_arguments(collect)
    collect.add_argument("--seed", type=int, default=0)
    collect.add_argument("--out", type=Path, default=None, help="default: <cache>/<domain>/data")
    collect.add_argument("--json", action="store_true", help="print a JSON summary")
    collect.set_defaults(func=run_collect)

    datasets = subparsers.add_parser("datasets", help="inspect data set files")
    verbs = datasets.add_subparsers(dest="datasets_command", metavar="VERB", required=True)
    info = verbs.add_parser("info", help="summary of a data set file (or every file in a dir)")
    info.add_argument("path", type=Path)
    info.add_argument("--json", action="store_true")
    info.set_defaults(func=run_info)
    add_minari_verbs(verbs)


def run_collect(args: argparse.Namespace) -> int:
    """Collect the requested skills and print their scripted success rates."""
    domain = domain_of(args)
    skills = list(domain.skills) if args.skill == "all" else [domain.skill(args.skill)]
    default = args.episodes is None
    counts = [
        (s, skill_episodes(domain, s, DEFAULT_EPISODES) if default else args.episodes)
        for s in skills
    ]
    out = check_output_dir(
        args.out or cache_dir() / domain.ref / "data", "data folder",
        collection_bytes(domain, counts),
    )  # fmt: skip
    rows = []
    with open_executor(args.backend, args.workers, args.address) as executor:
        for skill, episodes in counts:
            started = time.perf_counter()
            dataset = collect_skill(
                domain, skill, episodes, args.seed, out, executor, not args.json
            )
            summary = dataset_summary(dataset)
            summary["seconds"] = round(time.perf_counter() - started, 2)
            rows.append(summary)
    if args.json:
        print(dump_json(rows))
    else:
        print(f"{'skill':26s} {'episodes':>8s} {'steps':>7s} {'success':>8s} {'seconds':>8s}")
        for row in rows:
            print(
                f"{row['skill']:26s} {row['episodes']:8d} {row['steps']:7d} "
                f"{row['success_rate']:8.2f} {row['seconds']:8.1f}"
            )
        print(f"data sets in {out}")
    return 0


def run_info(args: argparse.Namespace) -> int:
    """Print one summary per file; a corrupt file is reported, not a crash."""
    paths = sorted(args.path.glob("*.h5")) if args.path.is_dir() else [args.path]
    rows = []
    status = 0
    for path in paths:
        try:
            rows.append(dataset_summary(load_dataset(path)))
        except DatasetError as err:
            rows.append({"path": str(path), "error": str(err)})
            status = 1
    if args.json:
        print(dump_json(rows))
        return status
    for row in rows:
        if "error" in row:
            print(f"{row['path']}: INVALID: {row['error']}")
            continue
        print(
            f"{row['path']}: skill {row['skill']}, {row['episodes']} episodes, {row['steps']} "
            f"steps, success rate {row['success_rate']:.2f}, seed {row['seed']}"
        )
        for name, shape in row["fields"].items():
            print(f"    {name:20s} {tuple(shape)}")
    return status
