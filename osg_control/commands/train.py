"""``osg train``: learn skills from their data sets with TD3+BC, all batched in one process.

A shell over ``osg_control.pipeline.train`` (arguments, printing, exit codes); the
training functions (``train_skills``, ``load_skill_input``, ``checkpoint_bytes``...) live
there.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from osg_control.commands import domain_of
from osg_control.paths import cache_dir
from osg_control.pipeline.train import (
    DEFAULT_STEPS,
    TrainedSkills,
    format_training,
    skill_names,
    train_skills,
)


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``train`` sub-command."""
    parser = subparsers.add_parser(
        "train",
        help="learn skills from their offline data sets (TD3+BC)",
        description="Train one skill, or all of them batched in one process, with TD3+BC "
        "from <DATA>/<skill>.h5, writing <OUT>/<skill>.safetensors and <OUT>/<skill>.json.",
    )
    parser.add_argument(
        "--skill",
        required=True,
        nargs="+",
        help="skill names (trained batched; each skill's weights do not depend on the "
        'others), or "all"',
    )
    parser.add_argument(
        "--steps", type=_positive_int, default=DEFAULT_STEPS, help="updates per skill"
    )
    parser.add_argument("--seed", type=int, default=0, help="run seed (default: 0)")
    parser.add_argument(
        "--data", type=Path, default=None, help="data set directory (default: <cache>/DOMAIN/data)"
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help="checkpoint directory (default: <cache>/DOMAIN/skills)",
    )
    parser.add_argument("--device", choices=("cpu", "cuda"), default="cpu")
    parser.add_argument(
        "--threads",
        type=_positive_int,
        default=None,
        help="CPU threads for torch (default: torch's, one per core; use fewer on a busy machine)",
    )
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.set_defaults(func=run)


def print_summary(trained: TrainedSkills, as_json: bool) -> None:
    """Print the run's summary as JSON or as one line per skill plus a total."""
    print(json.dumps(trained.to_dict(), indent=2) if as_json else format_training(trained))


def run(args: argparse.Namespace) -> int:
    """Train the selected skills batched and write their checkpoints."""
    domain = domain_of(args)
    trained = train_skills(
        domain,
        args.data or cache_dir() / domain.name / "data",
        args.out or cache_dir() / domain.name / "skills",
        skill_names(domain, args.skill),
        args.steps,
        args.seed,
        args.device,
        args.threads,
    )
    print_summary(trained, args.json)
    return 0
