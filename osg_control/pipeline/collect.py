"""Stage 1, collect: Algorithm 1's scripted noisy episodes, one HDF5 data set per skill.

Resumable: a finished data set with the same episodes, seed and spec is kept, and the
finished chunks of an interrupted collection are reused (``data.collect.collect_skill``).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from osg_control.data.collect import CHUNK_EPISODES, HOLD_STEPS, collect_skill
from osg_control.data.datasets import FILE_OVERHEAD, dataset_bytes, dataset_summary
from osg_control.domain.base import Domain
from osg_control.domain.spec import SkillSpec
from osg_control.io_safety import check_output_dir
from osg_control.learning.checkpoints import sha256_file
from osg_control.parallel import open_executor


@dataclass(frozen=True)
class DataSets:
    """The collected data sets.

    Attributes:
        directory: the folder holding ``<skill>.h5`` per skill.
        summaries: per skill, ``data.datasets.dataset_summary`` plus its ``seconds``.
    """

    directory: Path
    summaries: list[dict[str, Any]] = field(default_factory=list)

    def path(self, skill: str) -> Path:
        """The data set file of ``skill``."""
        return self.directory / f"{skill}.h5"

    def hashes(self) -> dict[str, str]:
        """File name -> sha256 of every data set in the folder (the bundle's provenance)."""
        return {p.name: sha256_file(p) for p in sorted(self.directory.glob("*.h5"))}


def skill_episodes(domain: Domain, skill: SkillSpec, episodes: int) -> int:
    """The episodes a run of ``episodes`` per skill collects of ``skill``: its training
    recipe's multiple of them (``Domain.recipe``)."""
    return episodes * domain.recipe(skill.name).episodes_factor


def collection_bytes(domain: Domain, counts: Sequence[tuple[SkillSpec, int]]) -> int:
    """The disk space collecting ``counts`` (each skill and its episodes) takes at most:
    every skill's merged file plus the chunk files of the skill in progress (each episode
    taken at its longest: the script's step budget plus the hold after a success)."""
    sizes = [
        dataset_bytes(
            episodes * (sum(skill.waypoint_budgets()) + HOLD_STEPS),
            episodes,
            len(domain.world_fields),
        )
        for skill, episodes in counts
    ]
    most = max((episodes for _skill, episodes in counts), default=1)
    chunk_files = -(-most // CHUNK_EPISODES)
    return sum(sizes) + max(sizes, default=0) + (chunk_files - 1) * FILE_OVERHEAD


def collect_datasets(
    domain: Domain,
    out: Path,
    episodes: int,
    seed: int = 0,
    workers: int = 1,
    skills: Sequence[str] | None = None,
    backend: str = "local",
    address: str | None = None,
    progress: bool = True,
) -> DataSets:
    """Collect ``episodes`` scripted episodes of each skill into ``out`` (a skill whose
    training recipe says so, a multiple of them: ``Domain.recipe``).

    Args:
        domain: whose skills to collect.
        out: the data folder (checked for room before any episode runs).
        episodes: per skill (before its recipe's ``episodes_factor``).
        seed: the run seed (each skill's episodes draw from it and the skill's name).
        workers: local processes (or Ray CPUs).
        skills: skill names (default: all of the domain's).
        backend: ``local`` or ``ray`` (``parallel.BACKENDS``).
        address: a Ray cluster address.
        progress: progress bars on stderr.

    Raises:
        OutputError: ``out`` cannot hold the data sets (before any work).
        SkillSpecError: an unknown skill name.
    """
    specs = list(domain.skills) if skills is None else [domain.skill(n) for n in skills]
    counts = [(spec, skill_episodes(domain, spec, episodes)) for spec in specs]
    folder = check_output_dir(out, "data folder", collection_bytes(domain, counts))
    summaries = []
    with open_executor(backend, workers, address) as executor:
        for spec, count in counts:
            started = time.perf_counter()
            dataset = collect_skill(domain, spec, count, seed, folder, executor, progress)
            summary = dataset_summary(dataset)
            summary["seconds"] = round(time.perf_counter() - started, 2)
            summaries.append(summary)
    return DataSets(folder, summaries)


def format_collection(datasets: DataSets) -> str:
    """One line per data set: episodes, steps, scripted success rate, seconds."""
    lines = [f"{'skill':26s} {'episodes':>8s} {'steps':>7s} {'success':>8s} {'seconds':>8s}"]
    for row in datasets.summaries:
        lines.append(
            f"{row['skill']:26s} {row['episodes']:8d} {row['steps']:7d} "
            f"{row['success_rate']:8.2f} {row['seconds']:8.1f}"
        )
    lines.append(f"data sets in {datasets.directory}")
    return "\n".join(lines)
