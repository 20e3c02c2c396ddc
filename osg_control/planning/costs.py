"""Plan costs from measured success rates: a defaults directory's manifest, as a skill graph.

A defaults directory's ``manifest.json`` records ``success_rates``, each skill's measured
Table I rate at the deployment noise; the graph built from them gives every operator the
cost ``round(-ln p * 1000)`` (``pddl_io.skill_cost``), the same in ``osg plan``, in the
exported PDDL and in the executor. Reading them needs no model (no torch).
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any

from osg_control.domain.base import Domain
from osg_control.errors import CheckpointError
from osg_control.json_files import is_json_number, read_json_object
from osg_control.planning.graph import SkillGraph, graph_from_specs

LOGGER = logging.getLogger(__name__)
MANIFEST = "manifest.json"
RATES_KEY = "success_rates"
"""The manifest's map of skill name -> measured success rate (the plan costs)."""


def measured_graph(domain: Domain, directory: str | Path | None = None) -> SkillGraph:
    """The domain's skill graph with the success rates of a defaults directory (default:
    the domain's shipped one; uniform costs when there is none)."""
    root = Path(directory) if directory is not None else domain.defaults_dir
    if root is None:
        return graph_from_specs(domain)
    if not (root / MANIFEST).exists():
        LOGGER.warning(
            "%s: no %s: planning at uniform skill costs (no measured success rates)",
            root,
            MANIFEST,
        )
    rates = success_rates(read_manifest(root), root / MANIFEST, domain)
    return graph_from_specs(domain, success_rates=rates)


def read_manifest(directory: Path) -> dict[str, Any]:
    """The manifest of a defaults directory (how its checkpoints were made); empty if the
    directory has none."""
    path = Path(directory) / MANIFEST
    if not path.exists():
        return {}
    return read_json_object(path, "manifest", CheckpointError)


def success_rates(manifest: dict[str, Any], path: Path, domain: Domain | None) -> dict[str, float]:
    """The manifest's measured success rates, checked: rates in [0, 1], and with a
    ``domain`` its skills only.

    Raises:
        CheckpointError: an unknown skill or a rate that is not a number in [0, 1].
    """
    rates = manifest.get(RATES_KEY, {})
    if not isinstance(rates, dict):
        raise CheckpointError(f"{path}: {RATES_KEY!r} must map skill names to rates")
    checked = {}
    for name, rate in rates.items():
        if domain is not None and name not in domain.skills_by_name:
            raise CheckpointError(f"{path}: {RATES_KEY!r} names unknown skill {name!r}")
        if not is_json_number(rate) or not math.isfinite(rate) or not 0 <= rate <= 1:
            raise CheckpointError(f"{path}: {RATES_KEY!r}[{name!r}] = {rate!r} is not in [0, 1]")
        checked[name] = float(rate)
    return checked
