"""Stage 2, train: TD3+BC skills from their data sets, all batched in one process
(``train_skills``), or only when the checkpoints there were not trained by this very
command on these very data (``train_missing``, ``resume.untrained_skills``).

With ``EarlyStop`` each skill leaves the batch once its held-out success stops improving
(``learning.early_stopping``) and keeps its best checked weights; the batch shrinks, and an
update costs in proportion to the skills left in it."""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch

from osg_control.data.datasets import load_dataset
from osg_control.domain.base import Domain
from osg_control.domain.spaces import ACTION_DIM, OBS_DIM
from osg_control.domain.spec import SkillSpec, skill_from_json
from osg_control.errors import DatasetError, OSGError, SkillSpecError
from osg_control.io_safety import check_output_dir
from osg_control.learning.checkpoints import Checkpoint, Layer, save_checkpoint, sha256_file
from osg_control.learning.replay import BatchedReplay, SkillData, prepare_skill_data
from osg_control.learning.td3bc import TD3BC, TD3BCConfig
from osg_control.pipeline.resume import untrained_skills
from osg_control.pipeline.training_loop import (
    EarlyStop,
    SkillOutcome,
    train_early_stopped,
    train_fixed,
)
from osg_control.seeding import skill_seed

DEFAULT_STEPS = 100_000
SIDECAR_BYTES = 16 * 2**10
"""Room allowed per checkpoint for its JSON sidecar and safetensors header (about 3 kB)."""


@dataclass
class SkillInput:
    """One skill's training input: its spec (as recorded in the data), data and provenance."""

    spec: SkillSpec
    data: SkillData
    dataset_path: Path
    dataset_sha256: str
    obs_noise: float = 0.0
    """Std [m] of its training noise on the sampled TCP position (``TD3BCConfig.obs_noise``)."""


@dataclass(frozen=True)
class TrainedSkills:
    """What a training run wrote.

    Attributes:
        directory: the checkpoint folder.
        device, threads: where it ran (torch's CPU threads).
        steps, seed: the update budget per skill and the run seed.
        seconds: the training time (loading and saving excluded; held-out checks included).
        check_seconds: of which the held-out checks (0 without early stopping).
        skills: per skill, its name, checkpoint and data set paths, data set hash, the
            updates of its weights (``updates``) and those it ran (``trained_updates``),
            its held-out checks (with early stopping) and its losses there.
    """

    directory: Path
    device: str
    threads: int
    steps: int
    seed: int
    seconds: float
    check_seconds: float = 0.0
    skills: list[dict[str, Any]] = field(default_factory=list)

    @property
    def skill_updates(self) -> int:
        """Updates run over all skills."""
        return sum(int(row["trained_updates"]) for row in self.skills)

    def to_dict(self) -> dict[str, Any]:
        """The summary ``osg train --json`` prints."""
        updating = max(self.seconds - self.check_seconds, 1e-9)
        return {
            "device": self.device,
            "threads": self.threads,
            "steps": self.steps,
            "seed": self.seed,
            "seconds": self.seconds,
            "check_seconds": self.check_seconds,
            "skill_updates": self.skill_updates,
            "updates_per_s": max((int(r["trained_updates"]) for r in self.skills), default=0)
            / updating,
            "skill_updates_per_s": self.skill_updates / updating,
            "skills": self.skills,
        }


def skill_names(domain: Domain, names: list[str]) -> list[str]:
    """Resolve skill names of the domain, or ``["all"]``.

    Raises:
        SkillSpecError: an unknown name, listing the known ones.
    """
    if names == ["all"]:
        return [skill.name for skill in domain.skills]
    return list(dict.fromkeys(domain.skill(name).name for name in names))


def load_skill_input(
    data_dir: Path, name: str, config: TD3BCConfig, action_scale: np.ndarray
) -> SkillInput:
    """Load and normalise ``<data_dir>/<name>.h5`` (observation eps from ``config``, actions
    per ``action_scale``: the domain's ``action_bounds``).

    Raises:
        DatasetError: naming the file: missing, malformed, recorded for another skill, or
            with no successful episode.
    """
    path = data_dir / f"{name}.h5"
    dataset = load_dataset(path)
    try:
        spec = skill_from_json(dataset.attrs["skill"])
    except SkillSpecError as err:
        raise DatasetError(f"{path}: invalid skill attribute ({err})") from err
    if spec.name != name:
        raise DatasetError(f"{path}: recorded for skill {spec.name!r}, not {name!r}")
    data = prepare_skill_data(dataset, action_scale, config.obs_norm_eps)
    return SkillInput(spec, data, path, sha256_file(path))


def checkpoint_bytes(config: TD3BCConfig, skills: int) -> int:
    """The disk space ``skills`` checkpoints take: the actor's float32 parameters (sized
    from ``config``'s layers) plus ``SIDECAR_BYTES`` each, known before any training."""
    sizes = (OBS_DIM, *config.hidden_sizes, ACTION_DIM)
    params = sum(n_in * n_out + n_out for n_in, n_out in itertools.pairwise(sizes))
    return skills * (4 * params + SIDECAR_BYTES)


def _checkpoint(
    item: SkillInput,
    layers: list[Layer],
    trainer: TD3BC,
    updates: int,
    seed: int,
    early_stopping: dict[str, Any] | None = None,
) -> Checkpoint:
    """A skill's checkpoint with ``layers`` after ``updates`` (``early_stopping``: its
    record in ``train_config``)."""
    train_config = replace(trainer.config, obs_noise=item.obs_noise).to_json_dict()
    if early_stopping is not None:
        train_config["early_stopping"] = early_stopping
    return Checkpoint(
        skill=item.spec,
        layers=layers,
        obs_mean=item.data.obs_mean,
        obs_std=item.data.obs_std,
        action_scale=item.data.action_scale,
        train_config=train_config,
        steps=updates,
        seed=seed,
        dataset_sha256=item.dataset_sha256,
    )


def save_checkpoints(
    out_dir: Path,
    inputs: list[SkillInput],
    trainer: TD3BC,
    outcomes: list[SkillOutcome],
    seed: int,
    steps: int,
    stop: EarlyStop | None = None,
) -> list[dict[str, Any]]:
    """Write every trained skill's checkpoint (``seed``: the run's; ``steps``: its budget).

    Returns:
        Per skill: its name, checkpoint and data set paths, data set hash, updates, held-out
        checks (with ``stop``) and logs.
    """
    results = []
    for item, outcome in zip(inputs, outcomes, strict=True):
        record = None
        if stop is not None and outcome.progress is not None:
            record = outcome.progress.to_json_dict(stop.record(), steps)
        checkpoint = _checkpoint(item, outcome.layers, trainer, outcome.updates, seed, record)
        weights, sidecar = save_checkpoint(out_dir, checkpoint)
        results.append(
            {
                "skill": item.spec.name,
                "weights": str(weights),
                "sidecar": str(sidecar),
                "dataset": str(item.dataset_path),
                "dataset_sha256": item.dataset_sha256,
                "updates": outcome.updates,
                "trained_updates": outcome.trained_updates,
                **({"held_out": record["checks"]} if record else {}),
                **outcome.logs,
            }
        )
    return results


def train_skills(
    domain: Domain,
    data_dir: Path,
    out_dir: Path,
    names: list[str] | None = None,
    steps: int = DEFAULT_STEPS,
    seed: int = 0,
    device: str = "cpu",
    threads: int | None = None,
    early_stop: EarlyStop | None = None,
    obs_noise: float | None = None,
) -> TrainedSkills:
    """Train skills batched with TD3+BC and write their checkpoints.

    Args:
        domain: the skills' domain (its ``action_bounds`` scale the actions).
        data_dir: ``<skill>.h5`` per skill.
        out_dir: the checkpoint folder (checked for room before any data is loaded).
        names: skill names (default: all of the domain's); each skill's weights do not
            depend on the others but for their last bits.
        steps: updates per skill (with ``early_stop``: the most).
        seed: the run seed (each skill's seed derives from it and the skill's name).
        device: ``cpu`` or ``cuda``.
        threads: torch CPU threads (None: torch's default); set process-wide.
        early_stop: stop each skill when its held-out success stops improving (None:
            every skill trains ``steps`` updates).
        obs_noise: std [m] of the noise on the sampled observations' TCP position
            (``TD3BCConfig.obs_noise``; recorded in each sidecar's ``train_config``) for
            every skill; None: each skill's training recipe's (``Domain.recipe``).

    Raises:
        OSGError: ``cuda`` without CUDA.
        OutputError: ``out_dir`` cannot hold the checkpoints.
        DatasetError: a data set missing or malformed, named.
        TrainingError: a non-finite loss (nothing saved).
    """
    names = [s.name for s in domain.skills] if names is None else names
    if device == "cuda" and not torch.cuda.is_available():
        raise OSGError("--device cuda: CUDA is not available on this machine")
    if threads:
        torch.set_num_threads(threads)
    config = TD3BCConfig()
    snapshots = 1 if early_stop is None else 2  # early stopping keeps one round's snapshot
    out = check_output_dir(
        out_dir, "checkpoint folder", snapshots * checkpoint_bytes(config, len(names))
    )
    bounds = np.asarray(domain.action_bounds, dtype=np.float32)
    inputs = [
        replace(
            load_skill_input(Path(data_dir), n, config, bounds),
            obs_noise=domain.recipe(n).obs_noise if obs_noise is None else obs_noise,
        )
        for n in names
    ]
    seeds = [skill_seed(seed, name) for name in names]
    replay = BatchedReplay(
        [i.data for i in inputs], config.batch_size, seeds, device, [i.obs_noise for i in inputs]
    )
    trainer = TD3BC(config, seeds, device=device)
    start = time.perf_counter()
    check_seconds = 0.0
    if early_stop is None:
        outcomes = train_fixed(trainer, replay, steps, names)
    else:

        def snapshot(folder: Path, layers: dict[str, list[Layer]], updates: int) -> None:
            for item in inputs:
                if item.spec.name in layers:
                    save_checkpoint(
                        folder, _checkpoint(item, layers[item.spec.name], trainer, updates, seed)
                    )

        outcomes, check_seconds = train_early_stopped(
            trainer, replay, names, steps, early_stop, snapshot, scratch_in=out
        )
    seconds = time.perf_counter() - start
    return TrainedSkills(
        directory=out,
        device=device,
        threads=torch.get_num_threads(),
        steps=steps,
        seed=seed,
        seconds=seconds,
        check_seconds=check_seconds,
        skills=save_checkpoints(out, inputs, trainer, outcomes, seed, steps, early_stop),
    )


def format_training(trained: TrainedSkills) -> str:
    """One line per skill (updates, held-out checks, losses, sidecar) and a total."""
    lines = []
    for r in trained.skills:
        checks = r.get("held_out")
        held_out = (
            " (held-out " + ", ".join(f"{u}: {rate:.2f}" for u, rate in checks) + ")"
            if checks
            else ""
        )
        lines.append(
            f"{r['skill']}: {r['updates']} updates{held_out}, critic loss "
            f"{r['critic_loss']:.4g}, bc loss {r.get('bc_loss', float('nan')):.4g} -> "
            f"{r['sidecar']}"
        )
    summary = trained.to_dict()
    checks = f", held-out checks {trained.check_seconds:.1f} s" if trained.check_seconds else ""
    lines.append(
        f"{len(trained.skills)} skill(s), {trained.skill_updates} skill-updates of at most "
        f"{trained.steps} each, in {trained.seconds:.1f} s{checks} "
        f"({summary['skill_updates_per_s']:.0f} skill-updates/s) on {trained.device}"
    )
    return "\n".join(lines)


def train_missing(
    domain: Domain,
    data_dir: Path,
    out_dir: Path,
    steps: int,
    seed: int = 0,
    device: str = "cpu",
    threads: int | None = None,
    early_stop: EarlyStop | None = None,
) -> TrainedSkills | None:
    """Train every skill batched unless all of them already have checkpoints trained with
    these steps, seed and stopping rule on these data sets (``untrained_skills``); None
    when nothing was trained. See ``train_skills`` for the arguments and errors."""
    record = None if early_stop is None else early_stop.record()
    if not untrained_skills(domain, Path(data_dir), Path(out_dir), steps, seed, record):
        return None
    return train_skills(domain, data_dir, out_dir, None, steps, seed, device, threads, early_stop)
