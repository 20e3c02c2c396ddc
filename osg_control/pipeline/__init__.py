"""The pipeline as a library: its stages as functions over typed artifacts.

In run order (``reproduce`` runs them all; ``osg train`` and ``osg reproduce`` are shells
over them):

- ``collect_datasets(domain, out, episodes, seed, workers) -> DataSets`` (``collect``)
- ``train_skills(domain, data_dir, out_dir, names, steps, seed, early_stop=...) ->
  TrainedSkills`` (fixed updates, or each skill stopped when its held-out success stops
  improving: ``training_loop``, ``held_out``), and
  ``train_missing(...) -> TrainedSkills | None``, which keeps checkpoints already trained
  on these data (``untrained_skills``) (``train``)
- ``table_i(domain, skills_dir, episodes, ...) -> dict``, then
  ``measured_rates(table) -> MeasuredRates`` and ``bundle_with_rates(bundle, measured)``
  (``tables``)
- ``export_measured_pddl(domain, data_dir, rates, out) -> ExportedPlan``: graph and PDDL
  whose costs are the measured rates' ``round(-ln p * 1000)`` (``export``)
- ``train_state_classifier(domain, data_dir, out, seed) -> TrainedClassifier``
  (``classifier``)
- ``table_ii``, ``table_iii``, ``tables_iv_v(domain, bundle, ...) -> dict`` (``tables``)
- ``reproduce(ReproduceConfig(domain, out, ...), log) -> Reproduction``: all of them and
  the report (``reproduction``)

The stages read and write a defaults folder through ``execution.bundle.ModelBundle``
(its manifest, typed). Names are imported on first use, so importing this package loads
neither torch nor MuJoCo.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS: dict[str, str] = {
    "DataSets": "collect",
    "collect_datasets": "collect",
    "fit_filter_motion": "motion",
    "TrainedSkills": "train",
    "train_skills": "train",
    "train_missing": "train",
    "untrained_skills": "resume",
    "MeasuredRates": "tables",
    "table_i": "tables",
    "deployment_rates": "tables",
    "measured_rates": "tables",
    "bundle_with_rates": "tables",
    "table_ii": "tables",
    "table_iii": "tables",
    "tables_iv_v": "tables",
    "ExportedPlan": "export",
    "export_measured_pddl": "export",
    "TrainedClassifier": "classifier",
    "train_state_classifier": "classifier",
    "Scale": "reproduction",
    "FULL": "reproduction",
    "QUICK": "reproduction",
    "with_early_stopping": "reproduction",
    "ReproduceConfig": "reproduction",
    "Reproduction": "reproduction",
    "StageError": "reproduction",
    "reproduce": "reproduction",
}
"""Public name -> the sub-module that defines it."""

__all__ = [
    "DataSets",
    "fit_filter_motion",
    "ExportedPlan",
    "FULL",
    "MeasuredRates",
    "QUICK",
    "ReproduceConfig",
    "Reproduction",
    "Scale",
    "StageError",
    "TrainedClassifier",
    "TrainedSkills",
    "bundle_with_rates",
    "collect_datasets",
    "deployment_rates",
    "export_measured_pddl",
    "measured_rates",
    "reproduce",
    "table_i",
    "table_ii",
    "table_iii",
    "tables_iv_v",
    "train_missing",
    "train_skills",
    "train_state_classifier",
    "untrained_skills",
    "with_early_stopping",
]


def __getattr__(name: str) -> Any:
    """Import a public name's sub-module on first use."""
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
