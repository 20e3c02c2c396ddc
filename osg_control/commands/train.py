"""``osg train``: learn skills from their data sets with TD3+BC, all batched in one process.

A shell over ``osg_control.pipeline.train`` (arguments, printing, exit codes); the
training functions (``train_skills``, ``load_skill_input``, ``checkpoint_bytes``...) live
there.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from osg_control.commands import (
    add_filter_argument,
    add_perception_arguments,
    domain_of,
    perception_of,
)
from osg_control.domain.base import Domain
from osg_control.execution.bundle import DEPLOYMENT_NOISE
from osg_control.json_files import dump_json
from osg_control.learning.early_stopping import CHECK_EPISODES, EarlyStopping
from osg_control.parallel.machine import machine_cpus
from osg_control.paths import cache_dir
from osg_control.pipeline.train import (
    DEFAULT_STEPS,
    TrainedSkills,
    format_training,
    skill_names,
    train_skills,
)
from osg_control.pipeline.training_loop import EarlyStop


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
    parser.add_argument(
        "--obs-noise",
        type=float,
        default=None,
        metavar="SIGMA",
        help="std [m] of Gaussian noise added to the TCP position of every sampled "
        "observation, so the policy learns from readings as noisy as at run time (default: "
        "each skill's training recipe's, 0 for most: the data as recorded)",
    )
    add_early_stop_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.set_defaults(func=run)


def add_early_stop_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--early-stop`` and its settings (``learning.early_stopping``)."""
    rule = EarlyStopping()
    group = parser.add_argument_group(
        "early stopping",
        "stop each skill when its success on held-out episodes (at Table I's deployment "
        "column: the perception's noise, the TCP filter) stops improving; --steps is then "
        "the most updates a skill gets",
    )
    group.add_argument("--early-stop", action="store_true", help="turn it on")
    group.add_argument(
        "--check-every",
        type=_positive_int,
        default=rule.check_every,
        help=f"updates between checks (default {rule.check_every})",
    )
    group.add_argument(
        "--patience",
        type=_positive_int,
        default=rule.patience,
        help=f"checks without improvement before a skill stops (default {rule.patience})",
    )
    group.add_argument(
        "--check-episodes",
        type=_positive_int,
        default=CHECK_EPISODES,
        help=f"held-out episodes per skill per check (default {CHECK_EPISODES})",
    )
    cpus = machine_cpus()
    group.add_argument(
        "--workers",
        type=_positive_int,
        default=cpus,
        help=f"processes for the checks (default: this machine's CPUs, {cpus})",
    )
    group.add_argument(
        "--noise", type=float, default=None, help="the paper protocol's TCP noise [m] (0.02)"
    )
    add_perception_arguments(group)
    add_filter_argument(group)


def early_stop_of(args: argparse.Namespace, domain: Domain, data_dir: Path) -> EarlyStop | None:
    """The early stopping the command line asks for (the filter's motion model fitted on
    the data in ``data_dir``), or None.

    Raises:
        UsageError: a perception the domain does not support (exit 2).
    """
    perception = perception_of(args, domain, default_noise=DEPLOYMENT_NOISE)
    if not args.early_stop:
        return None
    from osg_control.control.estimator import MOTION_MODEL
    from osg_control.pipeline.held_out import HeldOutCheck
    from osg_control.pipeline.motion import fit_filter_motion

    motion = fit_filter_motion(domain, data_dir) if args.filter is not None else MOTION_MODEL
    check = HeldOutCheck(
        domain, args.check_episodes, args.seed, args.workers, perception, args.filter, motion
    )
    return EarlyStop(EarlyStopping(args.check_every, args.patience), check)


def print_summary(trained: TrainedSkills, as_json: bool) -> None:
    """Print the run's summary as JSON or as one line per skill plus a total."""
    print(dump_json(trained.to_dict()) if as_json else format_training(trained))


def run(args: argparse.Namespace) -> int:
    """Train the selected skills batched and write their checkpoints."""
    domain = domain_of(args)
    data_dir = args.data or cache_dir() / domain.ref / "data"
    trained = train_skills(
        domain,
        data_dir,
        args.out or cache_dir() / domain.ref / "skills",
        skill_names(domain, args.skill),
        args.steps,
        args.seed,
        args.device,
        args.threads,
        early_stop_of(args, domain, data_dir),
        args.obs_noise,
    )
    print_summary(trained, args.json)
    return 0
