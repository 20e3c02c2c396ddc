"""Write a project data set as a Minari data set, with h5py and json only (no minari).

Layout (Minari's HDF5 storage, read by ``minari.load_dataset(ID)`` when
``MINARI_DATASETS_PATH`` is ``ROOT``)::

    ROOT/<namespace>/<name>-v<N>/data/
        metadata.json      dataset_id, totals, data_format "hdf5", the serialised
                           observation/action spaces (the domain's: its action
                           bounds, its robot's observation bounds), env_spec (e.g.
                           osg/Kitchen-v0 with the skill), minari_version, and the
                           source's osg_* attributes
        main_data.hdf5     episode_<i>/ (attrs id, total_steps)
                               observations (T+1, 10) float32: the T states, then the last
                                                               next state
                               actions (T, 7) float32, rewards (T,) float32,
                               terminations (T,) bool, truncations (T,) bool
                               infos/world_states (T, 11) float32: the world after each step

``terminations`` keep the project's meaning (every step at beta, including the hold steps),
so every array reads back equal to the source.
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from osg_control import __version__
from osg_control.data.datasets import Dataset, hdf5_bytes, load_dataset
from osg_control.domain.base import Domain
from osg_control.errors import DatasetError
from osg_control.io_safety import atomic_folder, refuse_package

MINARI_FORMAT_VERSION = "0.5.0"
"""The Minari data-set version written: its HDF5 layout, read by minari 0.5.x."""
DATASET_ID = re.compile(r"^(?:[-_\w][-_\w/]*[-_\w]+/)?[-_\w]+?-v\d+$")
"""Minari's ``(namespace/)name-vN`` (a version is required here)."""
DATA_DIR = "data"
MAIN_FILE = "main_data.hdf5"
METADATA_FILE = "metadata.json"


def minari_root() -> Path:
    """Where Minari looks for data sets: ``$MINARI_DATASETS_PATH``, else ~/.minari/datasets."""
    env = os.environ.get("MINARI_DATASETS_PATH")
    return Path(env) if env else Path.home() / ".minari" / "datasets"


def check_dataset_id(dataset_id: str) -> str:
    """Return ``dataset_id`` if it is ``(namespace/)name-vN``; else raise ``DatasetError``."""
    if not DATASET_ID.fullmatch(dataset_id):
        raise DatasetError(
            f"Minari data set id {dataset_id!r} is not NAMESPACE/NAME-vN (e.g. lab/my-skill-v0)"
        )
    return dataset_id


def box_space(low: np.ndarray, high: np.ndarray, dtype: str) -> str:
    """A Gymnasium Box serialised the way Minari writes it (a JSON string)."""
    return json.dumps(
        {
            "type": "Box",
            "dtype": dtype,
            "shape": list(np.shape(low)),
            "low": np.asarray(low, dtype=dtype).tolist(),
            "high": np.asarray(high, dtype=dtype).tolist(),
        }
    )


def _env_spec(env_id: str | None, skill: str) -> str | None:
    """The Gymnasium spec of the domain's env made for ``skill`` (None: no registered env)."""
    if env_id is None:
        return None
    import gymnasium

    from osg_control.registration import register_envs

    register_envs()
    return dataclasses.replace(gymnasium.spec(env_id), kwargs={"skill": skill}).to_json()


def _metadata(data: Dataset, dataset_id: str, domain: Domain) -> dict[str, Any]:
    """Minari's metadata of ``data``: its spaces are the domain's (``action_bounds``, the
    robot's ``observation_bounds``)."""
    bounds = np.asarray(domain.action_bounds, dtype=float)
    return {
        "dataset_id": dataset_id,
        "total_episodes": data.num_episodes,
        "total_steps": data.num_steps,
        "data_format": "hdf5",
        "jpeg_encoding": False,
        "observation_space": box_space(*domain.observation_bounds(), "float32"),
        "action_space": box_space(-bounds, bounds, "float32"),
        "env_spec": _env_spec(domain.env_id, data.skill_name),
        "minari_version": MINARI_FORMAT_VERSION,
        "algorithm_name": str(data.attrs.get("collector", "osg-control")),
        "description": f"osg-control data set of skill {data.skill_name} ({data.path.name})",
        "requirements": [f"osg-control>={__version__}"],
        "osg_skill": str(data.attrs["skill"]),
        "osg_seed": int(data.attrs["seed"]),
        "osg_world_fields": str(data.attrs.get("world_fields", "")),
        "osg_package_version": str(data.attrs.get("package_version", "")),
    }


def _episodes_bytes(data: Dataset) -> bytes:
    """Minari's ``main_data.hdf5`` of ``data``, built in memory (one group per episode).

    Raises:
        DatasetError: an episode's next observations do not chain with its observations.
    """

    def fill(f: h5py.File) -> None:
        for index in range(data.num_episodes):
            episode = data.episode(index)
            if not np.array_equal(episode.observations[1:], episode.next_observations[:-1]):
                raise DatasetError(
                    f"{data.path}: episode {index}: next_observations do not chain with "
                    f"observations, so they cannot be stored as Minari's T+1 observations"
                )
            group = f.create_group(f"episode_{index}")
            group.attrs["id"] = index
            group.attrs["total_steps"] = len(episode)
            group["observations"] = np.concatenate(
                [episode.observations, episode.next_observations[-1:]]
            ).astype(np.float32)
            group["actions"] = episode.actions.astype(np.float32)
            group["rewards"] = episode.rewards.astype(np.float32)
            group["terminations"] = episode.terminations.astype(bool)
            group["truncations"] = episode.truncations.astype(bool)
            group.create_group("infos")["world_states"] = episode.world_states.astype(np.float32)

    return hdf5_bytes(fill, track_order=True)


def export_minari(
    source: str | Path,
    dataset_id: str,
    domain: Domain,
    root: Path | None = None,
    force: bool = False,
) -> Path:
    """Write the data set file ``source`` as Minari data set ``dataset_id`` under ``root``.

    Args:
        domain: the data's domain: its spaces and its env's Gymnasium id (``env_id``,
            recorded as the data set's env spec).
        root: the Minari data-sets folder (default: ``minari_root()``).
        force: replace an existing data set of that id.

    Returns:
        The data set's folder ``root/dataset_id`` (Minari reads its ``data/``).

    Raises:
        DatasetError: a malformed id, an existing folder without ``force``, or a source
            that is not a valid project data set.
    """
    check_dataset_id(dataset_id)
    data = load_dataset(source)
    target = (root or minari_root()) / dataset_id
    refuse_package(target)
    if target.exists() and not force:
        raise DatasetError(f"{target} exists; pass --force to replace it")
    episodes = _episodes_bytes(data)
    metadata = _metadata(data, dataset_id, domain)
    metadata["dataset_size"] = round(len(episodes) / 1e6, 1)

    def fill(staging: Path) -> None:
        (staging / DATA_DIR).mkdir()
        (staging / DATA_DIR / MAIN_FILE).write_bytes(episodes)
        (staging / DATA_DIR / METADATA_FILE).write_text(json.dumps(metadata, indent=2))

    return atomic_folder(target, fill)
