"""Training's held-out checks (``learning.early_stopping``): each skill still training run on
episodes Table I never draws, at Table I's deployment column (its noise, perception and
TCP filter), so the weights a skill keeps are chosen on other episodes than those scoring it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from osg_control.control.estimator import MOTION_MODEL
from osg_control.domain.base import Domain
from osg_control.evaluation.skill_table import learned_rates
from osg_control.parallel import LocalExecutor
from osg_control.perception.spec import PerceptionSpec
from osg_control.pipeline.tables import deployment_noise

HELD_OUT_CELL = 1000
"""The episode cell of the checks (``evaluate.episode_rng``); Table I's columns are cells
0, 1, 2, so no check episode is a Table I episode."""


@dataclass(frozen=True)
class HeldOutCheck:
    """Runs skills from a checkpoint folder on held-out episodes.

    Attributes:
        domain: the skills' domain.
        episodes: per skill per check.
        seed: the run seed (the episodes' starts derive from it, each skill and the cell).
        workers: local processes.
        perception: what the policies perceive (Table I's; its deployment noise applies).
        filter_gain: the TCP filter gain (None: raw observations).
        filter_motion: the filter's motion model.
    """

    domain: Domain
    episodes: int
    seed: int = 0
    workers: int = 1
    perception: PerceptionSpec = field(default_factory=PerceptionSpec)
    filter_gain: float | None = None
    filter_motion: tuple[float, float] = MOTION_MODEL

    def __call__(self, policy_dir: Path, names: Sequence[str]) -> dict[str, float]:
        """Each named skill's success rate from ``policy_dir`` on the held-out episodes."""
        rates = learned_rates(
            self.domain, policy_dir, names, (deployment_noise(self.perception),), self.episodes,
            self.seed, LocalExecutor(self.workers), self.perception, self.filter_gain,
            filter_motion=self.filter_motion, first_cell=HELD_OUT_CELL,
        )  # fmt: skip
        return {name: float(rates[i, 0]) for i, name in enumerate(names)}

    def describe(self) -> dict[str, Any]:
        """What the checks ran under (recorded with the stopping rule)."""
        return {
            "episodes": self.episodes,
            "seed": self.seed,
            "cell": HELD_OUT_CELL,
            "perception": self.perception.to_dict(),
            "tcp_noise": deployment_noise(self.perception),
            "filter_gain": self.filter_gain,
        }
