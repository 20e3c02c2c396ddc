"""Stage 2, train: TD3+BC skills from their data sets, all batched in one process
(``train_skills``), or only when the checkpoints there were not trained by this very
command on these very data (``train_missing``, ``resume.untrained_skills``)."""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

from osg_control.data.datasets import ACTION_DIM, OBS_DIM, load_dataset
from osg_control.domain.base import Domain
from osg_control.domain.spec import SkillSpec, skill_from_json
from osg_control.errors import DatasetError, OSGError, SkillSpecError, TrainingError
from osg_control.io_safety import check_output_dir
from osg_control.learning.checkpoints import Checkpoint, save_checkpoint, sha256_file
from osg_control.learning.td3bc import (
    ACTION_SCALE,
    TD3BC,
    BatchedReplay,
    SkillData,
    TD3BCConfig,
    prepare_skill_data,
)
from osg_control.pipeline.resume import untrained_skills
from osg_control.seeding import skill_seed

DEFAULT_STEPS = 100_000
LOG_EVERY = 100
"""Updates between refreshes of the progress bar's losses."""
SIDECAR_BYTES = 16 * 2**10
"""Room allowed per checkpoint for its JSON sidecar and safetensors header (about 3 kB)."""


@dataclass
class SkillInput:
    """One skill's training input: its spec (as recorded in the data), data and provenance."""

    spec: SkillSpec
    data: SkillData
    dataset_path: Path
    dataset_sha256: str


@dataclass(frozen=True)
class TrainedSkills:
    """What a training run wrote.

    Attributes:
        directory: the checkpoint folder.
        device, threads: where it ran (torch's CPU threads).
        steps, seed: updates per skill and the run seed.
        seconds: the training time (loading and saving excluded).
        skills: per skill, its name, checkpoint and data set paths, data set hash and
            final losses.
    """

    directory: Path
    device: str
    threads: int
    steps: int
    seed: int
    seconds: float
    skills: list[dict[str, Any]] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """The summary ``osg train --json`` prints."""
        seconds = max(self.seconds, 1e-9)
        return {
            "device": self.device,
            "threads": self.threads,
            "steps": self.steps,
            "seed": self.seed,
            "seconds": self.seconds,
            "updates_per_s": self.steps / seconds,
            "skill_updates_per_s": self.steps * len(self.skills) / seconds,
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
    data_dir: Path, name: str, config: TD3BCConfig, action_scale: np.ndarray = ACTION_SCALE
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
    trainer: TD3BC, replay: BatchedReplay, steps: int, names: list[str] | None = None
) -> dict[str, torch.Tensor]:
    """Run ``steps`` updates under a progress bar (updates/s, losses averaged over skills).

    Returns:
        The latest per-skill (K,) value of every log key (actor keys from the last actor step).
    """
    logs: dict[str, torch.Tensor] = {}
    names = names or [str(k) for k in range(trainer.num_skills)]
    desc = f"train {trainer.num_skills} skill(s)"
    with tqdm(total=steps, desc=desc, unit="update", mininterval=0.5) as bar:
        for step in range(1, steps + 1):
            logs.update(trainer.train_step(replay.sample()))
            if step % LOG_EVERY == 0 or step == steps:
                check_finite_losses(logs, step, names)
                shown = ("critic_loss", "actor_loss", "bc_loss")
                postfix = {key: f"{logs[key].mean().item():.4g}" for key in shown if key in logs}
                bar.set_postfix(postfix, refresh=False)
            bar.update()
    return logs


def save_checkpoints(
    out_dir: Path,
    inputs: list[SkillInput],
    trainer: TD3BC,
    logs: dict[str, torch.Tensor],
    seed: int,
) -> list[dict[str, Any]]:
    """Write every trained skill's checkpoint (``seed``: the run's).

    Returns:
        Per skill: its name, checkpoint and data set paths, data set hash and final logs.
    """
    results = []
    for k, item in enumerate(inputs):
        checkpoint = Checkpoint(
            skill=item.spec,
            layers=trainer.actor_layers(k),
            obs_mean=item.data.obs_mean,
            obs_std=item.data.obs_std,
            action_scale=item.data.action_scale,
            train_config=trainer.config.to_json_dict(),
            steps=trainer.steps,
            seed=seed,
            dataset_sha256=item.dataset_sha256,
        )
        weights, sidecar = save_checkpoint(out_dir, checkpoint)
        results.append(
            {
                "skill": item.spec.name,
                "weights": str(weights),
                "sidecar": str(sidecar),
                "dataset": str(item.dataset_path),
                "dataset_sha256": item.dataset_sha256,
                **{key: float(value[k]) for key, value in sorted(logs.items())},
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
) -> TrainedSkills:
    """Train skills batched with TD3+BC and write their checkpoints.

    Args:
        domain: the skills' domain (its ``action_bounds`` scale the actions).
        data_dir: ``<skill>.h5`` per skill.
        out_dir: the checkpoint folder (checked for room before any data is loaded).
        names: skill names (default: all of the domain's); each skill's weights do not
            depend on the others but for their last bits.
        steps: updates per skill.
        seed: the run seed (each skill's seed derives from it and the skill's name).
        device: ``cpu`` or ``cuda``.
        threads: torch CPU threads (None: torch's default); set process-wide.

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
    out = check_output_dir(out_dir, "checkpoint folder", checkpoint_bytes(config, len(names)))
    bounds = np.asarray(domain.action_bounds, dtype=np.float32)
    inputs = [load_skill_input(Path(data_dir), n, config, bounds) for n in names]
    seeds = [skill_seed(seed, name) for name in names]
    replay = BatchedReplay([i.data for i in inputs], config.batch_size, seeds, device)
    trainer = TD3BC(config, seeds, device=device)
    start = time.perf_counter()
    logs = train_with_progress(trainer, replay, steps, names)
    seconds = time.perf_counter() - start
    return TrainedSkills(
        directory=out,
        device=device,
        threads=torch.get_num_threads(),
        steps=steps,
        seed=seed,
        seconds=seconds,
        skills=save_checkpoints(out, inputs, trainer, logs, seed),
    )


def format_training(trained: TrainedSkills) -> str:
    """One line per skill (losses, sidecar) and a total."""
    lines = [
        f"{r['skill']}: critic loss {r['critic_loss']:.4g}, "
        f"bc loss {r.get('bc_loss', float('nan')):.4g} -> {r['sidecar']}"
        for r in trained.skills
    ]
    summary = trained.to_dict()
    lines.append(
        f"{len(trained.skills)} skill(s) x {trained.steps} updates in {trained.seconds:.1f} s "
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
) -> TrainedSkills | None:
    """Train every skill batched unless all of them already have checkpoints trained with
    these steps and seed on these data sets (``untrained_skills``); None when nothing was
    trained. See ``train_skills`` for the arguments and errors."""
    if not untrained_skills(domain, Path(data_dir), Path(out_dir), steps, seed):
        return None
    return train_skills(domain, data_dir, out_dir, None, steps, seed, device, threads)
