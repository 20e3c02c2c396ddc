"""The training loops over a batch of TD3+BC skills: a fixed number of updates, or rounds
with held-out checks after which skills leave the batch (``learning.early_stopping``)."""

from __future__ import annotations

import shutil
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import torch
from tqdm import tqdm

from osg_control.errors import TrainingError
from osg_control.learning.checkpoints import Layer
from osg_control.learning.early_stopping import EarlyStopping, SkillProgress
from osg_control.learning.replay import BatchedReplay
from osg_control.learning.td3bc import TD3BC

LOG_EVERY = 100
"""Updates between refreshes of the progress bar's losses."""
Snapshot = Callable[[Path, dict[str, list[Layer]], int], None]
"""Writes the named skills' weights after that many updates into a folder, as checkpoints."""


class HeldOutRates(Protocol):
    """Success rates of checkpointed skills on held-out episodes (``held_out.HeldOutCheck``)."""

    def __call__(self, policy_dir: Path, names: Sequence[str]) -> Mapping[str, float]:
        """Each named skill's rate, run from the checkpoints in ``policy_dir``."""
        ...

    def describe(self) -> dict[str, Any]:
        """What the checks run under (JSON-ready)."""
        ...


@dataclass(frozen=True)
class EarlyStop:
    """Early stopping for a training run: the rule and the held-out check it consults."""

    rule: EarlyStopping
    check: HeldOutRates

    def record(self) -> dict[str, Any]:
        """The rule and the check's settings, as a checkpoint records them (and a rerun
        compares them, ``resume.untrained_skills``)."""
        return {**self.rule.to_json_dict(), "held_out": self.check.describe()}


@dataclass
class SkillOutcome:
    """What training left for one skill: the weights kept, their updates and losses, and
    (with early stopping) its held-out checks."""

    layers: list[Layer]
    updates: int
    logs: dict[str, float]
    progress: SkillProgress | None = None

    @property
    def trained_updates(self) -> int:
        """The updates it ran before it left the batch."""
        return self.progress.checks[-1][0] if self.progress else self.updates


def check_finite_losses(logs: dict[str, torch.Tensor], step: int, names: list[str]) -> None:
    """Stop training when a loss is NaN or infinite (its weights are garbage from then on).

    Raises:
        TrainingError: naming the loss, the skills and the update; nothing is saved.
    """
    for key, value in logs.items():
        bad = ~torch.isfinite(value)
        if bool(bad.any()):
            skills = [names[k] for k in torch.nonzero(bad.reshape(-1)).reshape(-1).tolist()]
            raise TrainingError(
                f"{key} is non-finite at update {step} for skill(s) {skills}; training stopped, "
                "no checkpoint written (check the data sets for extreme values)"
            )


def train_with_progress(
    trainer: TD3BC,
    replay: BatchedReplay,
    steps: int,
    names: list[str] | None = None,
    done: int = 0,
    budget: int | None = None,
) -> dict[str, torch.Tensor]:
    """Run ``steps`` updates under a progress bar (updates/s, losses averaged over skills),
    the bar counting from ``done`` of ``budget`` updates (default: 0 of ``steps``).

    Returns:
        The latest per-skill (K,) value of every log key (actor keys from the last actor step).
    """
    logs: dict[str, torch.Tensor] = {}
    names = names or [str(k) for k in range(trainer.num_skills)]
    desc = f"train {trainer.num_skills} skill(s)"
    total = budget or steps
    with tqdm(total=total, initial=done, desc=desc, unit="update", mininterval=0.5) as bar:
        for step in range(done + 1, done + steps + 1):
            logs.update(trainer.train_step(replay.sample()))
            if step % LOG_EVERY == 0 or step == done + steps:
                check_finite_losses(logs, step, names)
                shown = ("critic_loss", "actor_loss", "bc_loss")
                postfix = {key: f"{logs[key].mean().item():.4g}" for key in shown if key in logs}
                bar.set_postfix(postfix, refresh=False)
            bar.update()
    return logs


def _skill_logs(logs: dict[str, torch.Tensor], k: int) -> dict[str, float]:
    return {key: float(value[k]) for key, value in sorted(logs.items())}


def train_fixed(
    trainer: TD3BC, replay: BatchedReplay, steps: int, names: list[str]
) -> list[SkillOutcome]:
    """Every skill ``steps`` updates; each keeps its last weights."""
    logs = train_with_progress(trainer, replay, steps, names)
    return [
        SkillOutcome(trainer.actor_layers(k), steps, _skill_logs(logs, k))
        for k in range(len(names))
    ]


SCRATCH_PREFIX = ".osg-held-out-"
"""The name prefix of early stopping's scratch folder of held-out snapshots."""


def train_early_stopped(
    trainer: TD3BC,
    replay: BatchedReplay,
    names: list[str],
    steps: int,
    stop: EarlyStop,
    snapshot: Snapshot,
    scratch_in: Path | None = None,
) -> tuple[list[SkillOutcome], float]:
    """Train in rounds of ``check_every`` updates up to ``steps``; after each, check the
    skills still in the batch on held-out episodes (their current weights written to a
    scratch folder by ``snapshot``) and drop those the rule stops.

    The scratch folder (``SCRATCH_PREFIX``) lies in ``scratch_in`` (the checkpoint folder,
    whose free space was checked; None: the system's temporary folder) and holds one
    round's snapshot at a time: each is removed after its check, and scratch folders a
    killed run left there are removed at the start.

    Returns:
        Each skill's outcome (its best checked weights), in ``names`` order, and the
        seconds spent in checks.
    """
    active = list(names)
    progress = {name: SkillProgress() for name in active}
    kept: dict[str, SkillOutcome] = {}
    check_seconds, done = 0.0, 0
    if scratch_in is not None:
        for stale in Path(scratch_in).glob(f"{SCRATCH_PREFIX}*"):
            shutil.rmtree(stale, ignore_errors=True)  # left by a killed run
    with tempfile.TemporaryDirectory(prefix=SCRATCH_PREFIX, dir=scratch_in) as scratch:
        while active:
            chunk = min(stop.rule.check_every, steps - done)
            logs = train_with_progress(trainer, replay, chunk, active, done, steps)
            done += chunk
            started = time.perf_counter()
            folder = Path(scratch) / str(done)
            current = {name: trainer.actor_layers(k) for k, name in enumerate(active)}
            snapshot(folder, current, done)
            rates = stop.check(folder, active)
            shutil.rmtree(folder, ignore_errors=True)  # one round's snapshot at a time
            check_seconds += time.perf_counter() - started
            for k, name in enumerate(active):
                if progress[name].record(done, float(rates[name])):
                    logged = _skill_logs(logs, k)
                    kept[name] = SkillOutcome(current[name], done, logged, progress[name])
            staying = [
                k for k, name in enumerate(active)
                if done < steps and not progress[name].stopped(stop.rule)
            ]  # fmt: skip
            if len(staying) < len(active):
                trainer.keep(staying)
                replay.keep(staying)
                active = [active[k] for k in staying]
    return [kept[name] for name in names], check_seconds
