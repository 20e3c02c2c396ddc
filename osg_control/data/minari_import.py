"""Turn a Minari data set into a project data set for one skill (h5py and json only).

The Minari data set must have the project's state and action layout: Box spaces of shapes
``(10,)`` and ``(7,)``. Each step's success, from which the rewards and terminations are
rebuilt, comes from either

- ``rewards``: a step succeeds when its reward is positive, or
- ``predicate``: the skill's success predicate over the recorded state after the step
  and the world state under ``infos/world_states`` (needed then).

World states absent from the source are stored as NaN (unknown): such data trains a skill,
but a skill graph cannot read effects from it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from osg_control.data.datasets import (
    ACTION_DIM,
    OBS_DIM,
    UNKNOWN,
    Dataset,
    Episode,
    load_dataset,
    write_episodes,
)
from osg_control.data.minari_export import DATA_DIR, MAIN_FILE, METADATA_FILE, minari_root
from osg_control.domain.base import Domain
from osg_control.domain.spec import SkillSpec
from osg_control.environment.arm_env import success_holds
from osg_control.errors import DatasetError

SUCCESS_SOURCES = ("rewards", "predicate")


def resolve(source: str | Path) -> Path:
    """The ``data/`` folder of a Minari data set given as a folder or as an id under
    ``minari_root()``."""
    for candidate in (Path(source), minari_root() / str(source)):
        for data_dir in (candidate, candidate / DATA_DIR):
            if (data_dir / METADATA_FILE).is_file():
                return data_dir
    raise DatasetError(
        f"no Minari data set at {source!r} (looked for {METADATA_FILE} in it, in its "
        f"{DATA_DIR}/ and under {minari_root()})"
    )


def _space_shape(metadata: dict[str, Any], key: str, path: Path) -> tuple[int, ...]:
    try:
        space = json.loads(metadata[key])
    except (KeyError, TypeError, ValueError) as err:
        raise DatasetError(f"{path}: no readable {key} in {METADATA_FILE}") from err
    if space.get("type") != "Box":
        raise DatasetError(f"{path}: {key} is a {space.get('type')} space, expected a Box")
    return tuple(space["shape"])


def check_layout(metadata: dict[str, Any], skill: SkillSpec, path: Path) -> None:
    """Raise ``DatasetError`` naming both shapes if the spaces are not the skill's."""
    for key, wanted in (("observation_space", (OBS_DIM,)), ("action_space", (ACTION_DIM,))):
        shape = _space_shape(metadata, key, path)
        if shape != wanted:
            raise DatasetError(
                f"{path}: {key} has shape {shape}, but skill {skill.name} needs {wanted}"
            )


def _successes(
    domain: Domain,
    skill: SkillSpec,
    next_obs: np.ndarray,
    rewards: np.ndarray,
    worlds: np.ndarray,
    how: str,
) -> np.ndarray:
    if how == "rewards":
        return rewards > 0
    end = domain.nodes[skill.end]
    return np.array(
        [
            success_holds(skill, end, obs[:3], float(obs[7]), domain.facts_of(world))
            for obs, world in zip(next_obs, worlds, strict=True)
        ],
        dtype=bool,
    )


def _episode(domain: Domain, group: h5py.Group, skill: SkillSpec, how: str, where: str) -> Episode:
    world_dim = len(domain.world_fields)
    observations = group["observations"][()]
    actions = group["actions"][()]
    steps = len(actions)
    if observations.shape != (steps + 1, OBS_DIM) or actions.shape != (steps, ACTION_DIM):
        raise DatasetError(
            f"{where}: observations {observations.shape} and actions {actions.shape}; "
            f"expected ({steps + 1}, {OBS_DIM}) and ({steps}, {ACTION_DIM})"
        )
    infos = group.get("infos")
    if infos is not None and "world_states" in infos:
        worlds = infos["world_states"][()]
        if worlds.shape != (steps, world_dim):
            raise DatasetError(
                f"{where}: infos/world_states has shape {worlds.shape}, expected "
                f"({steps}, {world_dim}) (domain {domain.name!r})"
            )
    elif how == "predicate":
        raise DatasetError(f"{where}: no infos/world_states, so --success predicate cannot run")
    else:
        worlds = np.full((steps, world_dim), np.nan)
    success = _successes(domain, skill, observations[1:], group["rewards"][()], worlds, how)
    return Episode(
        observations=observations[:-1].astype(np.float32),
        next_observations=observations[1:].astype(np.float32),
        actions=actions.astype(np.float32),
        rewards=success.astype(np.float32),
        terminations=success,
        truncations=group["truncations"][()].astype(bool),
        world_states=worlds.astype(np.float32),
    )


def import_minari(
    domain: Domain,
    source: str | Path,
    skill: str | SkillSpec,
    out: str | Path,
    success: str = "rewards",
) -> Dataset:
    """Convert a Minari data set (folder or id) into the project data set file ``out``.

    Raises:
        DatasetError: no data set there, spaces or arrays not the skill's layout (both
            shapes named), an unknown ``success`` source, or no world states for
            ``success="predicate"``.
    """
    if success not in SUCCESS_SOURCES:
        raise DatasetError(f"unknown success source {success!r}; known: rewards, predicate")
    skill = domain.skill(skill) if isinstance(skill, str) else skill
    data_dir = resolve(source)
    metadata = json.loads((data_dir / METADATA_FILE).read_text())
    check_layout(metadata, skill, data_dir)
    main = data_dir / MAIN_FILE
    try:
        with h5py.File(main, "r") as f:
            names = sorted(f, key=lambda name: int(name.rsplit("_", 1)[1]))
            episodes = [_episode(domain, f[n], skill, success, f"{main}:{n}") for n in names]
    except (OSError, KeyError, ValueError, IndexError) as err:
        raise DatasetError(f"{main}: not a readable Minari HDF5 file ({err})") from err
    attrs = {
        "domain": domain.name,
        "world_fields": ",".join(domain.world_fields),
        "skill": skill.to_json(),
        "seed": max(int(metadata.get("osg_seed", 0)), 0),
        "collector": f"imported from Minari data set {metadata.get('dataset_id', source)}",
        "success_from": success,
    }
    if any(np.isnan(e.world_states).all() for e in episodes):
        attrs["world_states"] = UNKNOWN
    write_episodes(Path(out), episodes, attrs)
    return load_dataset(out)
