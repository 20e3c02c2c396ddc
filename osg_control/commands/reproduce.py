"""``osg reproduce``: the whole pipeline from nothing to Tables I-V, with a report.

Stages: collect -> train (TD3+BC, all skills batched) -> skill graph + PDDL -> classifier ->
Table I -> Table II -> Table III -> Tables IV/V -> report. Each stage's time is printed and
recorded. The output directory's ``defaults/`` has the layout of the shipped defaults
(``skills/``, ``classifier/``, ``manifest.json`` with the Table I success rates at 2 cm
that become the plan costs); a domain's shipped defaults are a copy of it.
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from osg_control import __version__
from osg_control.commands import (
    add_filter_argument,
    add_perception_arguments,
    domain_of,
    perception_of,
)
from osg_control.domain.base import Domain
from osg_control.domain.registry import get_domain
from osg_control.domain.spec import SkillSpec
from osg_control.errors import EXIT_CODES, OSGError
from osg_control.io_safety import atomic_write, check_output_dir
from osg_control.learning.checkpoints import sha256_file
from osg_control.paths import PACKAGE_DIR
from osg_control.planning.costs import MANIFEST, RATES_KEY

DEPLOYMENT_NOISE = 0.02
"""The observation noise [m] whose Table I rates become the plan costs (the paper's 2 cm)."""


@dataclass(frozen=True)
class Scale:
    """How big each stage is."""

    episodes: int
    train_steps: int
    table_i_episodes: int
    reach_episodes: int
    task_episodes: int


FULL = Scale(
    episodes=300, train_steps=10000, table_i_episodes=200, reach_episodes=200, task_episodes=100
)
QUICK = Scale(episodes=40, train_steps=300, table_i_episodes=4, reach_episodes=2, task_episodes=1)


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``reproduce`` to the ``osg`` parser."""
    parser = subparsers.add_parser("reproduce", help="run the whole pipeline and write a report")
    parser.add_argument("--quick", action="store_true", help="a few-minute smoke run")
    parser.add_argument("--out", type=Path, default=Path("osg-reproduction"))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
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
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    parser.set_defaults(func=run)


def check_against_shipped(
    domain: Domain, figures: dict[str, Any], source: Path, as_json: bool
) -> int:
    """Compare figures (read from ``source``) with the domain's shipped ``figures.json``;
    print the verdict.

    Returns:
        0 when every cell of the shipped figures agrees, 1 otherwise.

    Raises:
        DatasetError: either side malformed, or a shipped cell missing from ``figures``
            (``evaluation.check.compare``): a comparison that cannot be made never passes.
    """
    from osg_control.evaluation.check import FIGURES, compare, read_figures
    from osg_control.execution.defaults import defaults_root

    shipped = defaults_root(domain) / FIGURES
    compared, mismatches = compare(read_figures(shipped), figures, str(shipped), str(source))
    if as_json:
        print(json.dumps({"compared": compared, "mismatches": [m.__dict__ for m in mismatches]}))
    else:
        print(f"check: {compared} cells compared, {len(mismatches)} outside the intervals")
        for m in mismatches:
            print(f"  {m.where}: shipped {m.shipped:.3f}, reproduced {m.reproduced:.3f}")
    return 1 if mismatches else 0


def _git_commit() -> str | None:
    try:
        result = subprocess.run(
            ["git", "rev-parse", "HEAD"],
            cwd=PACKAGE_DIR.parent,
            capture_output=True,
            text=True,
            check=True,
        )
    except (OSError, subprocess.CalledProcessError):
        return None
    return result.stdout.strip()


def run(args: argparse.Namespace) -> int:
    """Run every stage, print each stage's time, write the report."""
    from osg_control.cli import main as osg

    domain = domain_of(args)
    perception = perception_of(args, domain, default_noise=DEPLOYMENT_NOISE)  # refused: exit 2
    if args.compare is not None:
        from osg_control.evaluation.check import figures_file, read_figures

        report = figures_file(args.compare)
        return check_against_shipped(domain, read_figures(report), report, args.json)
    scale = QUICK if args.quick else FULL
    commit = _git_commit()  # the code that runs, read before the work (HEAD may move)
    out: Path = check_output_dir(args.out, "reproduction folder")
    data, defaults = out / "data", out / "defaults"
    seed, workers = str(args.seed), str(args.workers)
    stage_seconds: dict[str, float] = {}
    figures: dict[str, Any] = {}

    def stage(name: str, action: Callable[[], Any]) -> Any:
        print(f"== {name}", flush=True)
        started = time.perf_counter()
        value = action()
        stage_seconds[name] = round(time.perf_counter() - started, 1)
        print(f"== {name}: {stage_seconds[name]} s", flush=True)
        return value

    def cli(*argv: str) -> int:
        code = osg(["--domain", domain.name, *argv])
        if code == EXIT_CODES["interrupted"]:
            raise KeyboardInterrupt
        if code:
            raise OSGError(f"osg reproduce: stage 'osg {' '.join(argv)}' exited {code}")
        return code

    stage(
        "collect",
        lambda: cli(
            "collect",
            "--skill",
            "all",
            "--episodes",
            str(scale.episodes),
            "--workers",
            workers,
            "--seed",
            seed,
            "--out",
            str(data),
        ),
    )

    def train() -> int | None:
        if not untrained_skills(domain, data, defaults / "skills", scale.train_steps, args.seed):
            return None
        return cli(
            "train",
            "--skill",
            "all",
            "--steps",
            str(scale.train_steps),
            "--seed",
            seed,
            "--data",
            str(data),
            "--out",
            str(defaults / "skills"),
            "--threads",
            "2",
        )

    stage("train", train)
    stage(
        "graph+pddl",
        lambda: (
            cli(
                "graph",
                "--data",
                str(data),
                "--out",
                str(out / "graph.json"),
                "--png",
                str(out / "graph.png"),
            ),
            cli("pddl", "export", "--out", str(out / "pddl"), "--graph", str(out / "graph.json")),
        ),
    )
    stage(
        "classifier",
        lambda: cli(
            "classifier",
            "train",
            "--data",
            str(data),
            "--out",
            str(defaults / "classifier"),
            "--seed",
            seed,
        ),
    )
    manifest = _manifest(domain.name, data, args, scale, commit)
    _write_manifest(defaults, manifest)
    figures["table_i"] = stage("table I", lambda: _table_i(domain, defaults, scale, args))
    manifest[RATES_KEY] = deployment_rates(figures["table_i"])
    manifest["success_rates_from"] = f"Table I at sigma = {DEPLOYMENT_NOISE} m" + (
        f", TCP filter gain {args.filter}" if args.filter is not None else ", raw observations"
    )
    _write_manifest(defaults, manifest)
    figures["table_ii"] = stage("table II", lambda: _table_ii(domain, defaults, data, args.seed))
    figures["table_iii"] = stage("table III", lambda: _table_iii(domain, defaults, scale, args))
    figures["tables_iv_v"] = stage(
        "tables IV/V", lambda: _tables_iv_v(domain, defaults, scale, args)
    )
    figures["stage_seconds"] = stage_seconds
    figures["run"] = {
        "command": "osg " + " ".join(map(shlex.quote, sys.argv[1:])),
        "quick": args.quick,
        "seed": args.seed,
        "workers": args.workers,
        "package_version": __version__,
        "total_seconds": round(sum(stage_seconds.values()), 1),
    }
    from osg_control.evaluation.report import write_report

    written = write_report(figures, out, domain.published)
    if args.json:
        print(json.dumps(figures, indent=2))
    else:
        for name, seconds in stage_seconds.items():
            print(f"{name:14s} {seconds:8.1f} s")
        print("report: " + ", ".join(map(str, written)))
    if args.check:
        from osg_control.evaluation.check import FIGURES

        return check_against_shipped(domain, figures, out / FIGURES, args.json)
    return 0


def untrained_skills(domain: Domain, data: Path, skills: Path, steps: int, seed: int) -> list[str]:
    """The domain's skills whose checkpoint in ``skills`` was not trained by this stage's
    command on these very data sets (steps, seed, spec and the data set's sha256 in its
    sidecar). A rerun into the same ``--out`` keeps the checkpoints only if there are none:
    any other retrains every skill, because weights trained in a smaller batch of skills
    differ in the last bits from the batch of all (measured: three skills retrained alone
    differed from a fresh run's), and a reproduction must be a fresh run's bytes."""
    return [skill.name for skill in domain.skills if not _trained(skill, data, skills, steps, seed)]


def _trained(skill: SkillSpec, data: Path, skills: Path, steps: int, seed: int) -> bool:
    try:
        meta = json.loads((skills / f"{skill.name}.json").read_text())
        dataset_sha256 = sha256_file(data / f"{skill.name}.h5")
    except (OSError, ValueError):
        return False
    expected = {
        "steps": steps,
        "seed": seed,
        "skill_spec": json.loads(skill.to_json()),
        "dataset_sha256": dataset_sha256,
    }
    if not isinstance(meta, dict) or any(meta.get(k) != v for k, v in expected.items()):
        return False
    return (skills / f"{skill.name}.safetensors").exists()


def _write_manifest(defaults: Path, manifest: dict[str, Any]) -> None:
    text = json.dumps(manifest, indent=2)
    atomic_write(defaults / MANIFEST, lambda tmp: tmp.write_text(text))


def deployment_rates(table_i: dict[str, Any]) -> dict[str, float]:
    """Each skill's Table I rate at ``DEPLOYMENT_NOISE`` (the plan costs' rates; the only
    column under a perception other than the paper's)."""
    noise = list(table_i["noise"])
    column = noise.index(DEPLOYMENT_NOISE) if DEPLOYMENT_NOISE in noise else len(noise) - 1
    return {row["skill"]: float(row["rates"][column]) for row in table_i["rows"]}


def _manifest(
    domain: str, data: Path, args: argparse.Namespace, scale: Scale, commit: str | None
) -> dict[str, Any]:
    return {
        "domain": domain,
        "command": f"osg --domain {domain} reproduce{' --quick' if args.quick else ''}"
        f"{'' if args.filter is None else f' --filter {args.filter}'}"
        f"{'' if args.perception is None else f' --perception {args.perception}'}"
        f"{'' if args.object_noise is None else f' --object-noise {args.object_noise}'} "
        f"--seed {args.seed} --out {args.out}",
        "seed": args.seed,
        "perception": perception_of(args, get_domain(domain), DEPLOYMENT_NOISE).to_dict(),
        "filter_gain": args.filter,
        "scale": scale.__dict__,
        "package_version": __version__,
        "git_commit": commit,
        "datasets_sha256": {p.name: sha256_file(p) for p in sorted(data.glob("*.h5"))},
    }


def _table_i(
    domain: Domain, defaults: Path, scale: Scale, args: argparse.Namespace
) -> dict[str, Any]:
    from osg_control.evaluation.evaluate import format_skill_table, skill_table

    perception = perception_of(args, domain, default_noise=DEPLOYMENT_NOISE)
    paper = perception.name == "paper"
    table = skill_table(
        domain,
        defaults / "skills",
        (0.0, 0.01, DEPLOYMENT_NOISE) if paper else (0.0,),
        scale.table_i_episodes,
        args.seed,
        args.workers,
        scripted_episodes=max(scale.table_i_episodes, 20),
        filter_gain=args.filter,
        perception=perception,
    )
    print(format_skill_table(table))
    return table


def _table_ii(domain: Domain, defaults: Path, data: Path, seed: int) -> dict[str, Any]:
    from osg_control.classifier.data import class_starts, load_classifier_data, movement_classes
    from osg_control.classifier.metrics import format_report
    from osg_control.classifier.model import StateClassifier, evaluate

    classes = movement_classes(domain)
    model = StateClassifier.load(defaults / "classifier", classes)
    test = load_classifier_data(data, classes, seed).test
    report = evaluate(model, test, class_starts(domain, classes))
    print(format_report(report))
    return dict(report.to_dict())


def _table_iii(
    domain: Domain, defaults: Path, scale: Scale, args: argparse.Namespace
) -> dict[str, Any]:
    from osg_control.evaluation.evaluate import format_reach_table, reach_table

    perception = perception_of(args, domain)
    table = reach_table(
        domain,
        str(defaults),
        scale.reach_episodes,
        args.seed,
        args.workers,
        perception.tcp_noise,
        perception=perception,
    )
    print(format_reach_table(table))
    return table


def _tables_iv_v(
    domain: Domain, defaults: Path, scale: Scale, args: argparse.Namespace
) -> dict[str, Any]:
    from osg_control.evaluation.evaluate import format_task_table, task_table

    perception = perception_of(args, domain, default_noise=DEPLOYMENT_NOISE)
    table = task_table(
        domain,
        str(defaults),
        scale.task_episodes,
        args.seed,
        args.workers,
        perception.tcp_noise,
        filter_gain=args.filter,
        perception=perception,
    )
    print(format_task_table(table))
    return table
