"""A LIBERO operator's recorded data as HDF5: the project's data-set fields
(``data.datasets``) at the lifted widths (``features``), plus where each episode came from.

Flat step arrays (``N`` steps over all episodes)::

    observations       (N, 15) float32   lifted observation before the step (features.OBS_FIELDS)
    next_observations  (N, 15) float32   after it
    actions            (N, 5)  float32   lifted action commanded (features.ACTION_FIELDS)
    rewards            (N,)    float32   1.0 on the step after which the operator's effect
                                         is perceived (pick_place.holding_ok), else 0.0
    terminations       (N,)    bool      rewards > 0 (the episode ends there)
    truncations        (N,)    bool      the scripted controller's legs ran out first
    episode_ids        (N,)    int64

Per-episode arrays (``E``): ``episode_starts``, ``episode_lengths``, ``episode_successes``,
``episode_tasks`` and ``episode_init_states`` (the task index and fixed initial state it
was recorded in). Attributes: ``format`` (``FORMAT``), ``format_version``, ``domain``,
``suite``, ``operator``, ``skill`` (the skill's spec as JSON), ``seed``, ``noise_std``
(the exploration noise per action component), ``obs_fields``, ``action_fields``,
``package_version``. Every array carries the sha256 of its bytes (``datasets.CHECKSUM_ATTR``),
checked on load; a file is written in memory and renamed into place (``io_safety``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from osg_control import __version__
from osg_control.data.datasets import CHECKSUM_ATTR, Dataset, content_sha256, hdf5_bytes, read_field
from osg_control.data.datasets import STEP_FIELDS as PROJECT_FIELDS
from osg_control.data.validation import check_attrs, check_episode_index, check_step_fields
from osg_control.errors import DatasetError
from osg_control.io_safety import atomic_write
from osg_control.libero.features import ACTION_DIM, ACTION_FIELDS, OBS_DIM, OBS_FIELDS

FORMAT = "osg-libero-skill-data"
FORMAT_VERSION = 1
WIDTHS = {"observations": OBS_DIM, "next_observations": OBS_DIM, "actions": ACTION_DIM}
STEP_FIELDS: dict[str, tuple[tuple[int, ...], Any]] = {
    key: (((WIDTHS[key],) if key in WIDTHS else shape), dtype)
    for key, (shape, dtype) in PROJECT_FIELDS.items()
    if key != "world_states"
}
"""The project's step fields (``data.datasets``) at the lifted widths, without world states."""
EPISODE_FIELDS = ("episode_starts", "episode_lengths", "episode_successes", "episode_tasks",
                  "episode_init_states")  # fmt: skip


@dataclass
class Recorded:
    """One recorded operator run: its steps' arrays and where it ran."""

    observations: list[np.ndarray]
    actions: list[np.ndarray]
    next_observations: list[np.ndarray]
    success: bool
    task: int
    init_state: int


def _arrays(episodes: Sequence[Recorded]) -> dict[str, np.ndarray]:
    lengths = np.array([len(e.actions) for e in episodes], dtype=np.int64)
    rewards = np.concatenate([
        np.r_[np.zeros(len(e.actions) - 1), float(e.success)] for e in episodes
    ]).astype(np.float32) if episodes else np.zeros(0, np.float32)  # fmt: skip

    def stacked(key: str, width: int) -> np.ndarray:
        rows = [row for e in episodes for row in getattr(e, key)]
        return np.asarray(rows, dtype=np.float32).reshape(-1, width)

    return {
        "observations": stacked("observations", OBS_DIM),
        "next_observations": stacked("next_observations", OBS_DIM),
        "actions": stacked("actions", ACTION_DIM),
        "rewards": rewards,
        "terminations": rewards > 0,
        "truncations": np.concatenate(
            [np.r_[np.zeros(len(e.actions) - 1, bool), not e.success] for e in episodes]
        ).astype(bool)
        if episodes
        else np.zeros(0, bool),  # fmt: skip
        "episode_ids": np.repeat(np.arange(len(episodes), dtype=np.int64), lengths),
        "episode_starts": (np.cumsum(lengths) - lengths).astype(np.int64),
        "episode_lengths": lengths,
        "episode_successes": np.array([e.success for e in episodes], dtype=np.bool_),
        "episode_tasks": np.array([e.task for e in episodes], dtype=np.int64),
        "episode_init_states": np.array([e.init_state for e in episodes], dtype=np.int64),
    }


def _check(path: Path, arrays: dict[str, np.ndarray], attrs: dict[str, Any]) -> None:
    """What ``load_skill_data`` refuses, refused before a write too."""
    check_step_fields(path, arrays, STEP_FIELDS)
    check_episode_index(path, arrays, arrays)
    check_attrs(path, attrs)
    for key in ("episode_tasks", "episode_init_states"):
        if arrays[key].shape != arrays["episode_lengths"].shape:
            raise DatasetError(f"{path}: field {key!r} is not one entry per episode")
    if attrs.get("format") != FORMAT:
        raise DatasetError(f"{path}: not a LIBERO skill data file (format {attrs.get('format')!r})")
    for key, names in (("obs_fields", OBS_FIELDS), ("action_fields", ACTION_FIELDS)):
        if attrs.get(key) != ",".join(names):
            raise DatasetError(f"{path}: attribute {key!r} is not this version's {names}")


def write_skill_data(path: Path, episodes: Sequence[Recorded], attrs: dict[str, Any]) -> str:
    """Check and write ``episodes`` to ``path`` atomically; returns the file's sha256.

    Raises:
        DatasetError: a field ``load_skill_data`` would refuse (nothing written).
        OutputError: the file cannot be written.
    """
    arrays = _arrays(episodes)
    attrs = {"format": FORMAT, "format_version": FORMAT_VERSION, "domain": "libero",
             "obs_fields": ",".join(OBS_FIELDS), "action_fields": ",".join(ACTION_FIELDS),
             "package_version": __version__, **attrs}  # fmt: skip
    _check(path, arrays, attrs)

    def fill(f: h5py.File) -> None:
        for key, values in arrays.items():
            f.create_dataset(key, data=values).attrs[CHECKSUM_ATTR] = content_sha256(values)
        for key, value in attrs.items():
            f.attrs[key] = value

    data = hdf5_bytes(fill)
    atomic_write(path, lambda tmp: tmp.write_bytes(data))
    return content_sha256(np.frombuffer(data, dtype=np.uint8))


def load_skill_data(path: str | Path) -> Dataset:
    """Read and check a LIBERO skill data file, as the project's ``Dataset`` (which
    ``learning.replay.prepare_skill_data`` trains from); every array's checksum verified.

    Raises:
        DatasetError: naming the file and what is wrong (missing, not HDF5, another
            format, a missing or wrong checksum, a wrong shape, a non-finite value, an
            inconsistent episode index).
    """
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f"{path}: LIBERO skill data file not found")
    try:
        with h5py.File(path, "r") as f:
            arrays = {
                key: read_field(f, key, path, True) for key in (*STEP_FIELDS, *EPISODE_FIELDS)
            }
            attrs = {key: (value.item() if isinstance(value, np.generic) else value)
                     for key, value in f.attrs.items()}  # fmt: skip
    except DatasetError:
        raise
    except (OSError, KeyError, ValueError, TypeError) as err:
        raise DatasetError(f"{path}: not a readable HDF5 data set ({err})") from err
    _check(path, arrays, attrs)
    return Dataset(
        path=path,
        arrays={key: arrays[key] for key in STEP_FIELDS},
        episode_starts=arrays["episode_starts"],
        episode_lengths=arrays["episode_lengths"],
        episode_successes=arrays["episode_successes"].astype(bool),
        attrs={
            **attrs,
            "episode_tasks": arrays["episode_tasks"],
            "episode_init_states": arrays["episode_init_states"],
        },  # fmt: skip
    )


def merge(datasets: Sequence[Dataset]) -> Dataset:
    """Several files' episodes as one data set (their paths joined by ``+``), all
    recorded for the same skill.

    Raises:
        DatasetError: files of different skills, or none.
    """
    if not datasets:
        raise DatasetError("no LIBERO skill data files given")
    names = {d.skill_name for d in datasets}
    if len(names) != 1:
        raise DatasetError(f"data files of different skills: {', '.join(sorted(names))}")
    lengths = np.concatenate([d.episode_lengths for d in datasets])
    arrays = {key: np.concatenate([d.arrays[key] for d in datasets]) for key in STEP_FIELDS}
    arrays["episode_ids"] = np.repeat(np.arange(len(lengths), dtype=np.int64), lengths)
    return Dataset(
        path=Path("+".join(str(d.path) for d in datasets)),
        arrays=arrays,
        episode_starts=(np.cumsum(lengths) - lengths).astype(np.int64),
        episode_lengths=lengths,
        episode_successes=np.concatenate([d.episode_successes for d in datasets]),
        attrs={"skill": datasets[0].attrs["skill"], "seed": datasets[0].attrs["seed"]},
    )
