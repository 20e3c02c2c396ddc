"""Training a lifted LIBERO skill: the project's batched TD3+BC (``learning.td3bc``,
``learning.replay``) on an operator's recorded data (``skill_data``), one network for every
object of any type, saved as a checkpoint (``learning.checkpoints``: safetensors + JSON)
in a skills folder beside a ``manifest.json`` that says how it was made.

A skills folder (the shipped one is ``DEFAULTS_DIR``)::

    skills/<skill>.safetensors, skills/<skill>.json   the actor (checkpoints' format)
    manifest.json                                     MANIFEST_FORMAT: the command, seed,
                                                      updates, each data file's sha256,
                                                      episodes and scripted success rate,
                                                      the operators each skill runs, and
                                                      (once measured) ``success_rates``
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from osg_control import __version__
from osg_control.data.datasets import Dataset
from osg_control.errors import CheckpointError
from osg_control.execution.bundle import MANIFEST, RATES_KEY
from osg_control.io_safety import atomic_write
from osg_control.json_files import read_json_object
from osg_control.learning.checkpoints import Checkpoint, save_checkpoint, sha256_file
from osg_control.learning.td3bc import TD3BCConfig
from osg_control.libero.features import ACTION_DIM, ACTION_SCALE, OBS_DIM
from osg_control.libero.recording import OPERATORS, pick_skill
from osg_control.libero.skill_data import merge
from osg_control.paths import PACKAGE_DIR

DEFAULTS_DIR = PACKAGE_DIR / "libero" / "defaults"
"""The shipped skills folder (package data: ``*/defaults/**/*``)."""
SKILLS_DIR = "skills"
MANIFEST_FORMAT = "osg-libero-skills"
CONFIG = TD3BCConfig(gripper_switch_weight=1.0)
"""TD3+BC's settings: the project's defaults but for the gripper weight: the lifted
action's gripper is an absolute command (-1 open, 1 closed), not the kitchen's switch
among hold labels, so no step of it is singled out."""


def train_skill(
    datasets: Sequence[Dataset],
    steps: int,
    seed: int,
    config: TD3BCConfig = CONFIG,
    threads: int = 1,
) -> tuple[Checkpoint, dict[str, Any]]:
    """Train the data's skill for ``steps`` TD3+BC updates from ``seed`` on the CPU with
    ``threads`` threads; returns the checkpoint and the training's log (its CPU time and
    last losses). One thread by default: a network this small gains nothing from more, and
    on a loaded machine two took 11 times the CPU time per update (13 against 150 ms).

    Raises:
        DatasetError: files of different skills, or no successful episode.
    """
    import torch

    from osg_control.learning.replay import BatchedReplay, prepare_skill_data
    from osg_control.learning.td3bc import TD3BC

    torch.set_num_threads(threads)
    data = merge(datasets)
    skill = prepare_skill_data(data, ACTION_SCALE.astype(np.float32), config.obs_norm_eps)
    trainer = TD3BC(config, [seed], OBS_DIM, ACTION_DIM)
    replay = BatchedReplay([skill], config.batch_size, [seed], obs_noise=config.obs_noise)
    start = time.process_time()
    logs: dict[str, torch.Tensor] = {}
    for _ in range(steps):
        logs.update(trainer.train_step(replay.sample()))
    log = {"cpu_s": round(time.process_time() - start, 1),
           **{k: float(v[0]) for k, v in logs.items()}}  # fmt: skip
    spec = pick_skill(float(data_attrs(datasets)["noise_std"]))
    checkpoint = Checkpoint(
        skill=spec, layers=trainer.actor_layers(0), obs_mean=skill.obs_mean,
        obs_std=skill.obs_std, action_scale=skill.action_scale,
        train_config=config.to_json_dict(), steps=steps, seed=seed,
        dataset_sha256=data_sha256(datasets),
    )  # fmt: skip
    return checkpoint, log


def data_attrs(datasets: Sequence[Dataset]) -> dict[str, Any]:
    """The first file's attributes (the skill, noise and format every file shares)."""
    return datasets[0].attrs


def data_sha256(datasets: Sequence[Dataset]) -> str:
    """The digest of the data files' digests, in order (one file: its own sha256)."""
    hashes = [sha256_file(d.path) for d in datasets]
    return hashes[0] if len(hashes) == 1 else hashlib.sha256("".join(hashes).encode()).hexdigest()


def write_skills(
    out: Path, checkpoint: Checkpoint, datasets: Sequence[Dataset], command: str,
    log: dict[str, Any],
) -> Path:  # fmt: skip
    """Write the checkpoint under ``out/skills`` and ``out/manifest.json``, atomically."""
    save_checkpoint(out / SKILLS_DIR, checkpoint)
    name = checkpoint.skill.name
    manifest = {
        "format": MANIFEST_FORMAT,
        "domain": "libero",
        "command": command,
        "package_version": __version__,
        "skills": {name: {
            "operators": list(OPERATORS[name]), "seed": checkpoint.seed,
            "updates": checkpoint.steps, "train_cpu_s": log["cpu_s"],
            "data": [{"file": Path(d.path).name, "sha256": sha256_file(d.path),
                      "suite": str(d.attrs["suite"]), "command": str(d.attrs.get("command", "")),
                      "seed": int(d.attrs["seed"]), "episodes": d.num_episodes,
                      "steps": d.num_steps, "scripted_success_rate": round(d.success_rate, 4),
                      "tasks": sorted({int(t) for t in d.attrs["episode_tasks"]}),
                      "init_states": sorted({int(s) for s in d.attrs["episode_init_states"]})}
                     for d in datasets],
        }},
        RATES_KEY: {},
    }  # fmt: skip
    path = out / MANIFEST
    atomic_write(path, lambda tmp: tmp.write_text(json.dumps(manifest, indent=2) + "\n"))
    return path


def read_manifest(directory: Path) -> dict[str, Any]:
    """A skills folder's manifest, checked: its format and the skills it names.

    Raises:
        CheckpointError: the manifest is missing, not JSON, of another format, or names a
            skill this version does not know.
    """
    path = directory / MANIFEST
    if not path.is_file():
        raise CheckpointError(f"{path}: LIBERO skills manifest not found")
    manifest = read_json_object(path, "LIBERO skills manifest", CheckpointError)
    if manifest.get("format") != MANIFEST_FORMAT:
        raise CheckpointError(f"{path}: not a LIBERO skills manifest ({manifest.get('format')!r})")
    skills = manifest.get("skills")
    if not isinstance(skills, dict) or not skills or not set(skills) <= set(OPERATORS):
        raise CheckpointError(f"{path}: 'skills' must name skills of {sorted(OPERATORS)}")
    return manifest
