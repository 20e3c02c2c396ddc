"""The train stage's resume rule: which checkpoints a rerun keeps (no torch needed)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from osg_control.domain.base import Domain
from osg_control.domain.spec import SkillSpec
from osg_control.json_files import JSONFormatError, load_json
from osg_control.learning.checkpoints import sha256_file


def untrained_skills(
    domain: Domain,
    data: Path,
    skills: Path,
    steps: int,
    seed: int,
    early_stopping: dict[str, Any] | None = None,
) -> list[str]:
    """The domain's skills whose checkpoint in ``skills`` was not trained by this stage's
    command on these very data sets (seed, spec and the data set's sha256 in its sidecar;
    ``steps`` updates, or with ``early_stopping`` (``EarlyStop.record``) that rule with a
    budget of ``steps``; with its training recipe's observation noise, as ``osg reproduce``
    trains: a checkpoint of ``osg train --obs-noise`` with another is not this stage's).
    A rerun into the same folder keeps the checkpoints only if there are none: any other
    retrains every skill (``train_missing``), because weights trained in a smaller batch of
    skills differ in the last bits from the batch of all (measured: three skills retrained
    alone differed from a fresh run's), and a reproduction must be a fresh run's bytes."""
    rule = None if early_stopping is None else json.loads(json.dumps(early_stopping))
    return [
        skill.name
        for skill in domain.skills
        if not _trained(skill, domain.recipe(skill.name).obs_noise, data, skills, steps, seed, rule)
    ]


def _trained(
    skill: SkillSpec,
    obs_noise: float,
    data: Path,
    skills: Path,
    steps: int,
    seed: int,
    early_stopping: dict[str, Any] | None,
) -> bool:
    try:
        meta = load_json(skills / f"{skill.name}.json")
        dataset_sha256 = sha256_file(data / f"{skill.name}.h5")
    except (OSError, JSONFormatError):
        return False
    expected = {
        "seed": seed,
        "skill_spec": json.loads(skill.to_json()),
        "dataset_sha256": dataset_sha256,
    }
    if not isinstance(meta, dict) or any(meta.get(k) != v for k, v in expected.items()):
        return False
    config = meta.get("train_config")
    config = config if isinstance(config, dict) else {}
    if config.get("obs_noise", 0.0) != obs_noise:
        return False  # trained on other readings than this stage trains on
    stopped = config.get("early_stopping")
    if early_stopping is None:
        budget_matches = stopped is None and meta.get("steps") == steps
    else:
        budget_matches = isinstance(stopped, dict) and (
            stopped.get("rule") == early_stopping and stopped.get("max_updates") == steps
        )
    return budget_matches and (skills / f"{skill.name}.safetensors").exists()
