"""``osg reproduce``: the whole pipeline from nothing to Tables I-V, with a report.

A shell over ``osg_control.pipeline.reproduction`` (arguments, printing, exit codes). Stages:
collect -> train (TD3+BC, all skills batched) -> filter fit -> Table I -> its rates into
the manifest -> skill graph + PDDL with those rates as costs -> classifier -> Table II ->
Table III -> Tables IV/V -> report. Each stage's time is printed and recorded. The output
directory's ``defaults/`` has the layout of the shipped defaults (``skills/``,
``classifier/``, ``manifest.json`` with the Table I success rates at 2 cm that become the
plan costs); a domain's shipped defaults are a copy of it.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from osg_control.commands import (
    add_filter_argument,
    add_perception_arguments,
    domain_of,
    perception_of,
)
from osg_control.domain.base import Domain
from osg_control.execution.bundle import DEPLOYMENT_NOISE
from osg_control.json_files import dump_json
from osg_control.parallel.machine import machine_cpus

if TYPE_CHECKING:
    from osg_control.evaluation.check import Comparison

__all__ = ["register", "run", "shipped_check"]


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``reproduce`` to the ``osg`` parser."""
    parser = subparsers.add_parser("reproduce", help="run the whole pipeline and write a report")
    parser.add_argument("--quick", action="store_true", help="a few-minute smoke run")
    parser.add_argument("--out", type=Path, default=Path("osg-reproduction"))
    parser.add_argument("--seed", type=int, default=0)
    cpus = machine_cpus()
    parser.add_argument(
        "--workers",
        type=int,
        default=cpus,
        help=f"processes for collection and the tables (default: this machine's CPUs, {cpus}; "
        "the figures do not depend on it)",
    )
    parser.add_argument(
        "--threads",
        type=int,
        default=cpus,
        help=f"torch CPU threads for training (default: this machine's CPUs, {cpus}; the "
        "shipped defaults were trained with 2, and another count may change the weights by "
        "rounding)",
    )
    parser.add_argument(
        "--early-stop",
        action="store_true",
        help="stop training each skill once its held-out success stops improving (checks "
        "every tenth of the budget; about a third of the updates, but the kitchen's door tasks "
        "lose 2-3 points: docs/learning.md#early-stopping); off by default",
    )
    parser.add_argument(
        "--noise",
        type=float,
        default=None,
        help="the paper protocol's TCP noise for Tables IV/V [m] (default 0.02)",
    )
    add_perception_arguments(parser)
    add_filter_argument(parser)
    parser.add_argument(
        "--check",
        action="store_true",
        help="after the run, compare its figures with the domain's shipped ones within their "
        "99 %% confidence intervals (exit 1 on a mismatch)",
    )
    parser.add_argument(
        "--compare",
        type=Path,
        metavar="REPORT",
        help="compare an earlier reproduction's figures.json (file or folder) with the shipped "
        "ones, without running anything",
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="print one JSON document: the figures (with --check, its verdict under "
        '"check"); with --compare, the verdict',
    )
    parser.set_defaults(func=run)


def shipped_check(domain: Domain, figures: dict[str, Any], source: Path) -> Comparison:
    """Compare figures (read from ``source``) with the domain's shipped ``figures.json``.

    Raises:
        DatasetError: either side malformed, or a shipped cell missing from ``figures``
            (``evaluation.check.compare``): a comparison that cannot be made never passes.
    """
    from osg_control.evaluation.check import FIGURES, compare, read_figures
    from osg_control.execution.defaults import defaults_root

    shipped = defaults_root(domain) / FIGURES
    return compare(read_figures(shipped), figures, str(shipped), str(source))


def verdict_json(result: Comparison) -> dict[str, Any]:
    """A check's verdict as ``--json`` prints it: cells compared, mismatches, and the
    smallest difference each cell could have detected."""
    return {
        "compared": result.compared,
        "mismatches": [m.__dict__ for m in result.mismatches],
        "detectable_difference": {**result.summary(), "cells": result.detectable},
    }


def print_verdict(result: Comparison) -> None:
    """A check's verdict in words."""
    power = result.summary()
    print(
        f"check: {result.compared} cells compared, {len(result.mismatches)} outside the intervals"
    )
    print(
        f"  smallest difference it could detect, per cell: {_rate(power['smallest'])} to "
        f"{_rate(power['largest'])} (median {_rate(power['median'])}; least power: "
        f"{power['largest_at']})"
    )
    for m in result.mismatches:
        print(f"  {m.where}: shipped {m.shipped:.3f}, reproduced {m.reproduced:.3f}")


def exit_code(result: Comparison) -> int:
    """0 when every cell of the shipped figures agrees, 1 otherwise."""
    return 1 if result.mismatches else 0


def _rate(value: float | None) -> str:
    return "none" if value is None else f"{value:.3f}"


def manifest_command(domain: Domain, args: argparse.Namespace) -> str:
    """The command that reproduces this run (the manifest's ``command``): with the robot
    ``--robot`` chose, when it is not the domain's own."""
    robot = "" if domain.robot_is_default else f" --robot {domain.robot}"
    return (
        f"osg --domain {domain.name}{robot} reproduce{' --quick' if args.quick else ''}"
        f"{' --early-stop' if args.early_stop else ''}"
        f"{'' if args.filter is None else f' --filter {args.filter}'}"
        f"{'' if args.perception is None else f' --perception {args.perception}'}"
        f"{'' if args.object_noise is None else f' --object-noise {args.object_noise}'} "
        f"--seed {args.seed} --out {args.out}"
    )


def run(args: argparse.Namespace) -> int:
    """Run every stage (``pipeline.reproduce``), print each stage's time, write the report;
    with ``--compare``, only compare an earlier report; with ``--check``, compare this one.

    Returns:
        0; 1 when ``--check``/``--compare`` finds a mismatch. A failed stage raises
        ``StageError`` (exit 1), Ctrl-C exit 130, both keeping the finished stages.
    """
    domain = domain_of(args)
    perception = perception_of(args, domain, default_noise=DEPLOYMENT_NOISE)  # refused: exit 2
    if args.threads < 1 or args.workers < 1:
        from osg_control.errors import UsageError

        raise UsageError(
            f"--workers and --threads must be >= 1, got {args.workers} and {args.threads}"
        )
    if args.check and args.quick:
        from osg_control.errors import UsageError

        raise UsageError(
            "--check cannot be used with --quick: a quick run's cells have too few episodes "
            "to find a difference from the shipped figures (see evaluation/check.py)"
        )
    if args.compare is not None:
        from osg_control.evaluation.check import figures_file, read_figures

        report = figures_file(args.compare)
        compared = shipped_check(domain, read_figures(report), report)
        if args.json:
            print(dump_json(verdict_json(compared), indent=None))
        else:
            print_verdict(compared)
        return exit_code(compared)
    from osg_control.pipeline.reproduction import (
        FULL,
        QUICK,
        ReproduceConfig,
        reproduce,
        with_early_stopping,
    )

    scale = QUICK if args.quick else FULL
    config = ReproduceConfig(
        domain=domain,
        out=args.out,
        scale=with_early_stopping(scale) if args.early_stop else scale,
        seed=args.seed,
        workers=args.workers,
        perception=perception,
        reach_perception=perception_of(args, domain),
        filter_gain=args.filter,
        train_threads=args.threads,
        command=manifest_command(domain, args),
        invocation="osg " + " ".join(map(shlex.quote, sys.argv[1:])),
    )
    # With --json, stdout is one JSON document alone: the stages' text goes to stderr, and
    # --check's verdict joins the figures under "check".
    text_out = sys.stderr if args.json else sys.stdout
    done = reproduce(config, log=lambda text: print(text, file=text_out, flush=True))
    result: Comparison | None = None
    if args.check:
        from osg_control.evaluation.check import FIGURES

        result = shipped_check(domain, done.figures, done.out / FIGURES)
    if args.json:
        check = {} if result is None else {"check": verdict_json(result)}
        print(dump_json({**done.figures, **check}))
        return 0 if result is None else exit_code(result)
    for name, seconds in done.stage_seconds.items():
        print(f"{name:14s} {seconds:8.1f} s")
    print("report: " + ", ".join(map(str, done.report)))
    if result is None:
        return 0
    print_verdict(result)
    return exit_code(result)
