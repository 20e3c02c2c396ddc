"""The measuring stages: Table I (learned skills under noise) and the success rates it
measures, which become the plan costs, then Tables II (classifier), III (reaching the graph)
and IV/V (tasks, without and with replanning) on a model bundle.

Each returns the table as the evaluation layer builds it (a JSON-ready dict); the
``format_*`` functions of ``evaluation.evaluate`` and ``classifier.metrics`` print them.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from osg_control.control.estimator import MOTION_MODEL
from osg_control.domain.base import Domain
from osg_control.evaluation.evaluate import reach_table, task_table
from osg_control.evaluation.skill_table import skill_table
from osg_control.execution.bundle import DEPLOYMENT_NOISE, ModelBundle
from osg_control.perception.spec import PerceptionSpec

PAPER_NOISE_LEVELS = (0.0, 0.01, DEPLOYMENT_NOISE)
"""Table I's columns under the paper's protocol (one column, 0, under the others)."""


@dataclass(frozen=True)
class MeasuredRates:
    """The success rates Table I measured, and the noise of the column they came from.

    Attributes:
        rates: skill name -> success rate.
        noise: the paper protocol's TCP noise sigma [m] of that column.
        perception: the perception they were measured under (its TCP noise ``noise``).
        filter_gain: the TCP filter gain the policies ran with (None: raw observations).
    """

    rates: dict[str, float]
    noise: float
    perception: PerceptionSpec
    filter_gain: float | None


def table_i_noise_levels(perception: PerceptionSpec) -> tuple[float, ...]:
    """Table I's noise columns: the paper's 0/1/2 cm under its protocol, else none added."""
    return PAPER_NOISE_LEVELS if perception.name == "paper" else (0.0,)


def table_i(
    domain: Domain,
    skills_dir: Path,
    episodes: int,
    seed: int = 0,
    workers: int = 2,
    perception: PerceptionSpec | None = None,
    filter_gain: float | None = None,
    scripted_episodes: int | None = None,
    progress: bool = False,
    filter_motion: tuple[float, float] = MOTION_MODEL,
) -> dict[str, Any]:
    """Table I: every learned skill's success rate from its initiation region, per noise
    column (``table_i_noise_levels``), beside the scripted policy's.

    Args:
        skills_dir: the skill checkpoints (a bundle's ``policies_dir``).
        episodes: per cell.
        perception: what the policies perceive (default: the paper's protocol).
        filter_gain: run the policies on TCP filter estimates with this gain.
        scripted_episodes: episodes of the scripted policy per skill (default:
            ``max(episodes, 20)``).
        filter_motion: the filter's motion model (the domain's fit, ``pipeline.motion``).

    Raises:
        CheckpointError: a skill checkpoint missing or not the domain's.
    """
    perception = perception or PerceptionSpec("paper", tcp_noise=DEPLOYMENT_NOISE)
    return skill_table(
        domain,
        skills_dir,
        table_i_noise_levels(perception),
        episodes,
        seed,
        workers,
        scripted_episodes=max(episodes, 20) if scripted_episodes is None else scripted_episodes,
        filter_gain=filter_gain,
        progress=progress,
        perception=perception,
        filter_motion=filter_motion,
    )


def deployment_noise(perception: PerceptionSpec) -> float:
    """The TCP noise [m] of Table I's deployment column under ``perception``: the paper's
    ``DEPLOYMENT_NOISE`` under its protocol, else none added (the last column)."""
    levels = table_i_noise_levels(perception)
    return DEPLOYMENT_NOISE if DEPLOYMENT_NOISE in levels else levels[-1]


def deployment_column(table: dict[str, Any]) -> int:
    """The index of Table I's column at ``DEPLOYMENT_NOISE`` (the last column without it)."""
    noise = list(table["noise"])
    return noise.index(DEPLOYMENT_NOISE) if DEPLOYMENT_NOISE in noise else len(noise) - 1


def deployment_rates(table: dict[str, Any]) -> dict[str, float]:
    """Each skill's Table I rate at ``DEPLOYMENT_NOISE`` (the plan costs' rates; the only
    column under a perception other than the paper's)."""
    column = deployment_column(table)
    return {row["skill"]: float(row["rates"][column]) for row in table["rows"]}


def measured_rates(table: dict[str, Any]) -> MeasuredRates:
    """The plan costs' success rates of a Table I, with what they were measured under (the
    table's ``perception`` at its deployment column's noise, and its filter gain)."""
    noise = float(table["noise"][deployment_column(table)])
    recorded = table.get("perception")
    perception = PerceptionSpec(**recorded) if isinstance(recorded, dict) else PerceptionSpec()
    return MeasuredRates(
        rates=deployment_rates(table),
        noise=noise,
        perception=replace(perception, tcp_noise=noise),
        filter_gain=table.get("filter_gain"),
    )


def bundle_with_rates(bundle: ModelBundle, measured: MeasuredRates) -> ModelBundle:
    """``bundle`` with Table I's measured rates, perception, noise and filter gain."""
    return bundle.with_rates(
        measured.rates, measured.noise, measured.perception, measured.filter_gain
    )


def table_ii(domain: Domain, bundle: ModelBundle, data_dir: Path, seed: int = 0) -> dict[str, Any]:
    """Table II: the bundle's classifier on the held-out episodes of the movement data sets
    (split by ``seed``, as it was trained): confusion matrix, accuracy, corrected accuracy,
    the nearest-start-node baseline."""
    from osg_control.classifier.data import class_starts, load_classifier_data, movement_classes
    from osg_control.classifier.model import StateClassifier, evaluate

    classes = movement_classes(domain)
    model = StateClassifier.load(bundle.classifier_dir, classes)
    test = load_classifier_data(data_dir, classes, seed, domain=domain).test
    return dict(evaluate(model, test, class_starts(domain, classes)).to_dict())


def format_table_ii(table: dict[str, Any]) -> str:
    """Table II (a ``table_ii`` dict) as text, like the paper's."""
    from osg_control.classifier.metrics import EvaluationReport, format_report

    report = EvaluationReport(
        classes=tuple(table["classes"]),
        confusion=np.asarray(table["confusion"], dtype=float),
        num_states=int(table["num_states"]),
        baseline_accuracy=float(table["baseline_accuracy"]),
    )
    return format_report(report)


def table_iii(
    domain: Domain,
    bundle: ModelBundle,
    episodes: int,
    seed: int = 0,
    workers: int = 2,
    perception: PerceptionSpec | None = None,
    progress: bool = False,
) -> dict[str, Any]:
    """Table III: classify random starts around the start regions, run the chosen movement
    skill, count arrivals (``perception``'s TCP noise applies; default: none)."""
    perception = perception or PerceptionSpec()
    return reach_table(
        domain,
        str(bundle.directory),
        episodes,
        seed,
        workers,
        progress=progress,
        perception=perception,
    )


def tables_iv_v(
    domain: Domain,
    bundle: ModelBundle,
    episodes: int,
    seed: int = 0,
    workers: int = 2,
    perception: PerceptionSpec | None = None,
    filter_gain: float | None = None,
    progress: bool = False,
) -> dict[str, Any]:
    """Tables IV and V: every task from every start region, planned over the bundle's
    measured costs, without and with replanning (``perception``'s TCP noise applies;
    default: the paper's 2 cm)."""
    perception = perception or PerceptionSpec("paper", tcp_noise=DEPLOYMENT_NOISE)
    return task_table(
        domain,
        str(bundle.directory),
        episodes,
        seed,
        workers,
        filter_gain=filter_gain,
        progress=progress,
        perception=perception,
    )
