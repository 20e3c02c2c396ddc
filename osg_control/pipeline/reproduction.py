"""The whole pipeline, from nothing to Tables I-V and a report.

Stages, each timed: collect -> filter (the TCP filter's motion model fitted on the data) ->
train (TD3+BC, all skills batched, optionally each stopped when its held-out success stops
improving; kept when already trained on these data) -> Table I ->
the measured success rates into the bundle's manifest -> graph + PDDL with those rates as
costs -> classifier -> Table II -> Table III -> Tables IV/V -> report. The output folder's
``defaults/`` is a model bundle with the layout of the shipped defaults (``skills/``,
``classifier/``, ``manifest.json``); a domain's shipped defaults are a copy of it.
"""

from __future__ import annotations

import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any, TypeVar

from osg_control import __version__
from osg_control.domain.base import Domain
from osg_control.errors import OSGError
from osg_control.evaluation.evaluate import format_reach_table, format_task_table
from osg_control.evaluation.report import write_report
from osg_control.evaluation.skill_table import format_skill_table
from osg_control.execution.bundle import SKILLS_DIR, ModelBundle
from osg_control.io_safety import check_output_dir
from osg_control.learning.early_stopping import CHECK_EPISODES, EarlyStopping
from osg_control.paths import PACKAGE_DIR
from osg_control.perception.spec import PerceptionSpec
from osg_control.pipeline.classifier import (
    TrainedClassifier,
    format_classifier,
    train_state_classifier,
)
from osg_control.pipeline.collect import DataSets, collect_datasets, format_collection
from osg_control.pipeline.export import ExportedPlan, export_measured_pddl, format_export
from osg_control.pipeline.held_out import HeldOutCheck
from osg_control.pipeline.motion import fit_filter_motion, format_motion
from osg_control.pipeline.tables import (
    DEPLOYMENT_NOISE,
    bundle_with_rates,
    format_table_ii,
    measured_rates,
    table_i,
    table_ii,
    table_iii,
    tables_iv_v,
)
from osg_control.pipeline.train import TrainedSkills, format_training, train_missing
from osg_control.pipeline.training_loop import EarlyStop

T = TypeVar("T")
Log = Callable[[str], None]
"""Where the stages' text goes (stage times, tables); e.g. ``print``."""
DATA_DIR = "data"
DEFAULTS_DIR = "defaults"


@dataclass(frozen=True)
class Scale:
    """How big each stage is.

    Attributes:
        episodes: collected per skill.
        train_steps: TD3+BC updates per skill (with early stopping: the most).
        table_i_episodes, reach_episodes, task_episodes: per cell of Tables I, III, IV/V.
        check_every: updates between training's held-out checks (None: no early stopping,
            every skill trains ``train_steps``).
        patience: checks without improvement after which a skill stops.
        check_episodes: held-out episodes per skill per check.
    """

    episodes: int
    train_steps: int
    table_i_episodes: int
    reach_episodes: int
    task_episodes: int
    check_every: int | None = None
    patience: int = 2
    check_episodes: int = CHECK_EPISODES

    def early_stopping(self) -> EarlyStopping | None:
        """The training stage's stopping rule, if any."""
        if self.check_every is None:
            return None
        return EarlyStopping(self.check_every, self.patience)


FULL = Scale(
    episodes=300, train_steps=10000, table_i_episodes=200, reach_episodes=200, task_episodes=100
)
QUICK = Scale(episodes=40, train_steps=300, table_i_episodes=4, reach_episodes=2, task_episodes=1)
EARLY_STOP_EVERY = 0.1
"""``with_early_stopping``'s checks, as a fraction of the training budget (1,000 of 10,000)."""


def with_early_stopping(scale: Scale, patience: int = 2) -> Scale:
    """``scale`` with training stopped early per skill, checked every tenth of its budget
    on a quarter of Table I's episodes per cell (at least 2; ``FULL``: every 1,000 updates,
    50 episodes) (``osg reproduce --early-stop``). Off in ``FULL``: measured on the kitchen,
    it trains in 36 % of the updates at the same Table I, but the door tasks of Tables IV/V
    lose 2-3 points (docs/learning.md#early-stopping)."""
    every = max(1, round(scale.train_steps * EARLY_STOP_EVERY))
    episodes = max(2, scale.table_i_episodes // 4)
    return replace(scale, check_every=every, patience=patience, check_episodes=episodes)


class StageError(OSGError):
    """A stage failed; the message names the stage and its error (kept as ``__cause__``)."""

    def __init__(self, stage: str, error: Exception) -> None:
        super().__init__(f"stage {stage!r} failed: {error}")
        self.stage = stage


@dataclass(frozen=True)
class ReproduceConfig:
    """What to reproduce and how.

    Attributes:
        domain: the domain.
        out: the output folder (``data/``, ``defaults/``, graph, PDDL, report).
        scale: the stages' sizes (``FULL`` or ``QUICK``, or any ``Scale``).
        seed: the run seed of every stage.
        workers: local processes for collection and the tables.
        perception: what the robot perceives in Tables I and IV/V (its TCP noise: Tables
            IV/V's; Table I has its own columns).
        reach_perception: Table III's (default: ``perception`` without TCP noise).
        filter_gain: the TCP filter gain of Tables I and IV/V (None: raw observations).
        train_threads: torch CPU threads for training.
        command: the command that reproduces this run (the manifest's ``command``).
        invocation: the command as given (the report's ``run.command``).
        progress: progress bars on stderr for collection and the classifier.
    """

    domain: Domain
    out: Path
    scale: Scale = FULL
    seed: int = 0
    workers: int = 2
    perception: PerceptionSpec = field(
        default_factory=lambda: PerceptionSpec("paper", tcp_noise=DEPLOYMENT_NOISE)
    )
    reach_perception: PerceptionSpec | None = None
    filter_gain: float | None = None
    train_threads: int | None = 2
    command: str | None = None
    invocation: str | None = None
    progress: bool = True

    def table_iii_perception(self) -> PerceptionSpec:
        """Table III's perception."""
        if self.reach_perception is not None:
            return self.reach_perception
        return replace(self.perception, tcp_noise=0.0)

    def describe(self) -> str:
        """``command``, else this call in words."""
        return self.command or (
            f"osg_control.pipeline.reproduce(domain={self.domain.ref!r}, seed={self.seed}, "
            f"out={str(self.out)!r}, scale={self.scale}, perception={self.perception.name!r}, "
            f"filter_gain={self.filter_gain})"
        )


@dataclass(frozen=True)
class Reproduction:
    """What ``reproduce`` made.

    Attributes:
        out: the output folder.
        bundle: ``<out>/defaults``: skills, classifier, the measured success rates.
        datasets: ``<out>/data``.
        trained: the training run, or None when the checkpoints were kept.
        exported: the graph and PDDL (costs from the measured rates).
        classifier: the classifier stage's output.
        figures: every table, the stage times and the run's description (``figures.json``).
        report: the report files written.
    """

    out: Path
    bundle: ModelBundle
    datasets: DataSets
    trained: TrainedSkills | None
    exported: ExportedPlan
    classifier: TrainedClassifier
    figures: dict[str, Any]
    report: list[Path]

    @property
    def stage_seconds(self) -> dict[str, float]:
        """Each stage's wall time [s], in run order."""
        return dict(self.figures["stage_seconds"])


class StageClock:
    """Runs stages, logs their start, text and time, records ``seconds`` per stage; an
    ``OSGError`` inside a stage becomes a ``StageError`` naming it (Ctrl-C passes)."""

    def __init__(self, log: Log | None = None) -> None:
        self.log = log or (lambda _text: None)
        self.seconds: dict[str, float] = {}

    def run(self, name: str, action: Callable[[], T], text: Callable[[T], str] | None = None) -> T:
        """Run ``action`` as stage ``name`` and log ``text(value)``; its value."""
        self.log(f"== {name}")
        started = time.perf_counter()
        try:
            value = action()
        except StageError:
            raise
        except OSGError as err:
            raise StageError(name, err) from err
        if text is not None:
            self.log(text(value))
        self.seconds[name] = round(time.perf_counter() - started, 1)
        self.log(f"== {name}: {self.seconds[name]} s")
        return value


def git_commit() -> str | None:
    """The package checkout's ``HEAD`` commit, or None outside a git checkout."""
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


def reproduce(config: ReproduceConfig, log: Log | None = None) -> Reproduction:
    """Run every stage into ``config.out`` and write the report.

    Args:
        config: what and how.
        log: receives each stage's start and time and its text (tables, files written).

    Raises:
        OutputError: the output folder cannot be written (before any stage).
        StageError: a stage failed (its error as the cause; the stages before it kept).
        KeyboardInterrupt: interrupted (finished collection chunks and stages are kept).
    """
    say = log or (lambda _text: None)
    domain, scale, seed, workers = config.domain, config.scale, config.seed, config.workers
    commit = git_commit()  # the code that runs, read before the work (HEAD may move)
    out = check_output_dir(config.out, "reproduction folder")
    data_dir, defaults = out / DATA_DIR, out / DEFAULTS_DIR
    stages = StageClock(say)

    datasets = stages.run(
        "collect",
        partial(collect_datasets, domain, data_dir, scale.episodes, seed, workers,
                progress=config.progress),
        format_collection,
    )  # fmt: skip
    motion = stages.run("filter", partial(fit_filter_motion, domain, data_dir), format_motion)
    trained = stages.run(
        "train",
        partial(train_missing, domain, data_dir, defaults / SKILLS_DIR, scale.train_steps, seed,
                threads=config.train_threads, early_stop=training_early_stop(config, motion)),
        _format_trained,
    )  # fmt: skip
    bundle = ModelBundle(
        defaults,
        perception=config.perception,
        filter_gain=config.filter_gain,
        motion_model=motion,
        provenance={
            "domain": domain.name,
            "robot": domain.robot,
            "command": config.describe(),
            "seed": seed,
            "scale": scale.__dict__,
            "package_version": __version__,
            "git_commit": commit,
            "datasets_sha256": datasets.hashes(),
        },
    )
    bundle.write()
    figures: dict[str, Any] = {}
    figures["table_i"] = stages.run(
        "table I",
        partial(table_i, domain, bundle.policies_dir, scale.table_i_episodes, seed, workers,
                config.perception, config.filter_gain, filter_motion=motion),
        format_skill_table,
    )  # fmt: skip
    bundle = bundle_with_rates(bundle, measured_rates(figures["table_i"]))
    bundle.write()  # the plan costs of Tables III-V and of the PDDL
    exported = stages.run(
        "graph+pddl",
        partial(export_measured_pddl, domain, data_dir, bundle.success_rates, out),
        format_export,
    )
    classifier = stages.run(
        "classifier",
        partial(train_state_classifier, domain, data_dir, bundle.classifier_dir, seed,
                progress=config.progress),
        format_classifier,
    )  # fmt: skip
    figures["table_ii"] = stages.run(
        "table II", partial(table_ii, domain, bundle, data_dir, seed), format_table_ii
    )
    figures["table_iii"] = stages.run(
        "table III",
        partial(table_iii, domain, bundle, scale.reach_episodes, seed, workers,
                config.table_iii_perception()),
        format_reach_table,
    )  # fmt: skip
    figures["tables_iv_v"] = stages.run(
        "tables IV/V",
        partial(tables_iv_v, domain, bundle, scale.task_episodes, seed, workers,
                config.perception, config.filter_gain),
        format_task_table,
    )  # fmt: skip
    figures["stage_seconds"] = stages.seconds
    figures["run"] = {
        "command": config.invocation or config.describe(),
        "quick": scale == QUICK,
        "seed": seed,
        "workers": workers,
        "package_version": __version__,
        "total_seconds": round(sum(stages.seconds.values()), 1),
    }
    written = write_report(figures, out, domain.published)
    return Reproduction(out, bundle, datasets, trained, exported, classifier, figures, written)


def training_early_stop(config: ReproduceConfig, motion: tuple[float, float]) -> EarlyStop | None:
    """The train stage's early stopping: the scale's rule, checked at Table I's deployment
    column (its perception, filter and the fitted motion model) on held-out episodes."""
    rule = config.scale.early_stopping()
    if rule is None:
        return None
    check = HeldOutCheck(
        config.domain, config.scale.check_episodes, config.seed, config.workers,
        config.perception, config.filter_gain, motion,
    )  # fmt: skip
    return EarlyStop(rule, check)


def _format_trained(trained: TrainedSkills | None) -> str:
    if trained is None:
        return "checkpoints kept: every skill was trained with these steps on these data"
    return format_training(trained)
