"""``osg train``: learn skills from their data sets with TD3+BC, all batched in one process."""

from __future__ import annotations

import argparse
import itertools
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

from osg_control.commands import domain_of
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
from osg_control.paths import cache_dir
from osg_control.seeding import skill_seed

DEFAULT_STEPS = 100_000
LOG_EVERY = 100
"""Updates between refreshes of the progress bar's losses."""


@dataclass
class SkillInput:
    """One skill's training input: its spec (as recorded in the data), data and provenance."""

    spec: SkillSpec
    data: SkillData
    dataset_path: Path
    dataset_sha256: str


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``train`` sub-command."""
    parser = subparsers.add_parser(
        "train",
        help="learn skills from their offline data sets (TD3+BC)",
        description="Train one skill, or all of them batched in one process, with TD3+BC "
        "from <DATA>/<skill>.h5, writing <OUT>/<skill>.safetensors and <OUT>/<skill>.json.",
    )
    parser.add_argument(
        "--skill",
        required=True,
        nargs="+",
        help="skill names (trained batched; each skill's weights do not depend on the "
        'others), or "all"',
    )
    parser.add_argument(
        "--steps", type=_positive_int, default=DEFAULT_STEPS, help="updates per skill"
    )
    parser.add_argument("--seed", type=int, default=0, help="run seed (default: 0)")
    parser.add_argument(
        "--data", type=Path, default=None, help="data set directory (default: <cache>/DOMAIN/data)"
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help="checkpoint directory (default: <cache>/DOMAIN/skills)",
    )
    parser.add_argument("--device", choices=("cpu", "cuda"), default="cpu")
    parser.add_argument(
        "--threads",
        type=_positive_int,
        default=None,
        help="CPU threads for torch (default: torch's, one per core; use fewer on a busy machine)",
    )
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.set_defaults(func=run)


def skill_names(domain: Domain, names: list[str]) -> list[str]:
    """Resolve ``--skill``: skill names of the domain, or ``all``.

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


SIDECAR_BYTES = 16 * 2**10
"""Room allowed per checkpoint for its JSON sidecar and safetensors header (about 3 kB)."""


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
    """Write every trained skill's checkpoint (``seed``: the run's, as given to ``--seed``).

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


def print_summary(summary: dict[str, Any], as_json: bool) -> None:
    """Print the run's summary as JSON or as one line per skill plus a total."""
    if as_json:
        print(json.dumps(summary, indent=2))
        return
    for result in summary["skills"]:
        print(
            f"{result['skill']}: critic loss {result['critic_loss']:.4g}, "
            f"bc loss {result.get('bc_loss', float('nan')):.4g} -> {result['sidecar']}"
        )
    print(
        f"{len(summary['skills'])} skill(s) x {summary['steps']} updates in "
        f"{summary['seconds']:.1f} s ({summary['skill_updates_per_s']:.0f} skill-updates/s) "
        f"on {summary['device']}"
    )


def run(args: argparse.Namespace) -> int:
    """Train the selected skills batched and write their checkpoints."""
    domain = domain_of(args)
    names = skill_names(domain, args.skill)
    if args.device == "cuda" and not torch.cuda.is_available():
        raise OSGError("--device cuda: CUDA is not available on this machine")
    if args.threads:
        torch.set_num_threads(args.threads)
    config = TD3BCConfig()
    data_dir = args.data or cache_dir() / domain.name / "data"
    out_dir = check_output_dir(
        args.out or cache_dir() / domain.name / "skills",
        "checkpoint folder",
        checkpoint_bytes(config, len(names)),
    )
    bounds = np.asarray(domain.action_bounds, dtype=np.float32)
    inputs = [load_skill_input(data_dir, n, config, bounds) for n in names]
    seeds = [skill_seed(args.seed, name) for name in names]
    replay = BatchedReplay([i.data for i in inputs], config.batch_size, seeds, args.device)
    trainer = TD3BC(config, seeds, device=args.device)
    start = time.perf_counter()
    logs = train_with_progress(trainer, replay, args.steps, names)
    seconds = time.perf_counter() - start
    print_summary(
        {
            "device": args.device,
            "threads": torch.get_num_threads(),
            "steps": args.steps,
            "seed": args.seed,
            "seconds": seconds,
            "updates_per_s": args.steps / seconds,
            "skill_updates_per_s": args.steps * len(names) / seconds,
            "skills": save_checkpoints(out_dir, inputs, trainer, logs, args.seed),
        },
        args.json,
    )
    return 0
