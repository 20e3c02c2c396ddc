"""Offline data sets as HDF5: D4RL/Minari field names, readable with plain h5py.

One file per skill. Flat step arrays (``N`` steps over all episodes)::

    observations       (N, 10) float32   state before the step
    next_observations  (N, 10) float32   state after the step
    actions            (N, 7)  float32   the action applied (after clipping)
    rewards            (N,)    float32   1.0 on every step after which the success predicate
                                         holds (the paper: "whenever the robot achieves the
                                         task"), else 0.0
    terminations       (N,)    bool      the step reached beta: same as rewards > 0, so a
                                         TD target never bootstraps past a success
    truncations        (N,)    bool      episode ended by the step budget, not at beta

An episode is successful if any step is rewarded; after its first success the recording
continues for ``collect.HOLD_STEPS`` steps with the script holding its last waypoint.
    episode_ids        (N,)    int64     episode index of each step
    world_states       (N, W)  float32   world state after the step (the domain's
                                         ``world_fields``, named in the ``world_fields``
                                         attribute)

Per-episode arrays (``E`` episodes): ``episode_starts`` (offset of the first step),
``episode_lengths``, ``episode_successes``. Attributes: ``skill`` (the spec as JSON),
``seed``, ``package_version``, ``format_version``, ``world_fields`` (comma-separated),
``domain``.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from osg_control.data.validation import check_attrs, check_episode_index, check_step_fields
from osg_control.errors import DatasetError
from osg_control.io_safety import atomic_write

FORMAT_VERSION = 1
OBS_DIM = 10
ACTION_DIM = 7
UNKNOWN = "unknown"
"""``world_states`` attribute of a data set whose world states were not recorded (all NaN,
e.g. imported from elsewhere): it trains a skill, but yields no effects for the graph."""
WORLD_WIDTH = -1
"""Stands for the domain's world-state width in ``STEP_FIELDS`` (fixed per file)."""
STEP_FIELDS: dict[str, tuple[tuple[int, ...], Any]] = {
    "observations": ((OBS_DIM,), np.float32),
    "next_observations": ((OBS_DIM,), np.float32),
    "actions": ((ACTION_DIM,), np.float32),
    "rewards": ((), np.float32),
    "terminations": ((), np.bool_),
    "truncations": ((), np.bool_),
    "episode_ids": ((), np.int64),
    "world_states": ((WORLD_WIDTH,), np.float32),
}


@dataclass
class Episode:
    """One recorded episode (arrays over its T steps, field shapes as in ``STEP_FIELDS``)."""

    observations: np.ndarray
    next_observations: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    terminations: np.ndarray
    truncations: np.ndarray
    world_states: np.ndarray

    @property
    def success(self) -> bool:
        """Whether the episode got its reward."""
        return bool(self.rewards.sum() > 0)

    def __len__(self) -> int:
        return len(self.actions)


@dataclass
class Dataset:
    """A loaded data set: the step arrays, per-episode arrays and metadata."""

    path: Path
    arrays: dict[str, np.ndarray]
    episode_starts: np.ndarray
    episode_lengths: np.ndarray
    episode_successes: np.ndarray
    attrs: dict[str, Any]

    @property
    def num_episodes(self) -> int:
        """Episodes in the file."""
        return len(self.episode_lengths)

    @property
    def num_steps(self) -> int:
        """Steps over all episodes."""
        return len(self.arrays["actions"])

    @property
    def success_rate(self) -> float:
        """Fraction of episodes that reached the skill's success predicate."""
        return float(self.episode_successes.mean()) if self.num_episodes else 0.0

    @property
    def first_success_steps(self) -> np.ndarray:
        """Step index where each successful episode first reached beta, in episode order."""
        rewarded = np.flatnonzero(self.arrays["rewards"] > 0)
        _episodes, first = np.unique(self._step_episodes[rewarded], return_index=True)
        return rewarded[first]

    @property
    def approach_mask(self) -> np.ndarray:
        """(N,) bool: True up to and including the step that first reached beta; False on
        the steps recorded after it (``collect.HOLD_STEPS``). Failed episodes: all True."""
        episode = self._step_episodes
        firsts = self.first_success_steps
        last = np.full(self.num_episodes, self.num_steps)
        last[episode[firsts]] = firsts
        return np.arange(self.num_steps) <= last[episode]

    @property
    def _step_episodes(self) -> np.ndarray:
        """(N,) the index (in this file) of the episode each step belongs to."""
        return np.repeat(np.arange(self.num_episodes), self.episode_lengths)

    @property
    def skill_name(self) -> str:
        """The name of the skill recorded."""
        return str(json.loads(self.attrs["skill"])["name"])

    def episode(self, index: int) -> Episode:
        """Slice out one episode."""
        start = int(self.episode_starts[index])
        stop = start + int(self.episode_lengths[index])
        return Episode(
            **{key: self.arrays[key][start:stop] for key in STEP_FIELDS if key != "episode_ids"}
        )


def write_episodes(path: Path, episodes: Sequence[Episode], attrs: dict[str, Any]) -> None:
    """Write episodes to ``path`` atomically (a temp file renamed over the target).

    An interrupted write leaves the old file (or none), never a truncated one.
    """
    fields = attrs.get("world_fields")
    if not isinstance(fields, str) or not fields:
        raise DatasetError(f"{path}: attribute 'world_fields' (the world-state names) is required")
    world_shape = (len(fields.split(",")),)
    lengths = np.array([len(e) for e in episodes], dtype=np.int64)
    starts = (np.cumsum(lengths) - lengths).astype(np.int64)

    def write(tmp: Path) -> None:
        with h5py.File(tmp, "w") as f:
            for key, (declared, dtype) in STEP_FIELDS.items():
                shape = world_shape if declared == (WORLD_WIDTH,) else declared
                if key == "episode_ids":
                    values = np.repeat(np.arange(len(episodes), dtype=np.int64), lengths)
                elif episodes:
                    values = np.concatenate([getattr(e, key) for e in episodes]).astype(dtype)
                else:
                    values = np.zeros((0, *shape), dtype=dtype)
                f.create_dataset(key, data=values.reshape((-1, *shape)))
            f.create_dataset("episode_starts", data=starts)
            f.create_dataset("episode_lengths", data=lengths)
            f.create_dataset(
                "episode_successes", data=np.array([e.success for e in episodes], dtype=np.bool_)
            )
            f.attrs["format_version"] = FORMAT_VERSION
            for key, value in attrs.items():
                f.attrs[key] = value

    atomic_write(path, write)


def _world_width(f: h5py.File, path: Path) -> int:
    """The world-state width a file declares (its ``world_fields`` attribute)."""
    fields = f.attrs.get("world_fields")
    if not isinstance(fields, str) or not fields:
        raise DatasetError(f"{path}: missing attribute 'world_fields'")
    return len(fields.split(","))


def load_dataset(path: str | Path) -> Dataset:
    """Read and validate a data set file.

    Raises:
        DatasetError: naming the file and what is wrong (missing, not HDF5, missing field,
            wrong shape or dtype, non-finite values, an inconsistent episode index; see
            ``osg_control.data.validation``).
    """
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f"{path}: data set file not found")
    try:
        with h5py.File(path, "r") as f:
            arrays: dict[str, np.ndarray] = {}
            for key in STEP_FIELDS:
                if key not in f:
                    raise DatasetError(f"{path}: missing field {key!r}")
                arrays[key] = np.asarray(f[key][()])
            per_episode = {}
            for key in ("episode_starts", "episode_lengths", "episode_successes"):
                if key not in f:
                    raise DatasetError(f"{path}: missing field {key!r}")
                per_episode[key] = np.asarray(f[key][()])
            attrs = dict(f.attrs)
            fields = {
                key: ((_world_width(f, path),), dtype)
                if shape == (WORLD_WIDTH,)
                else (shape, dtype)
                for key, (shape, dtype) in STEP_FIELDS.items()
            }
    except DatasetError:
        raise
    except (OSError, KeyError, ValueError, TypeError) as err:
        raise DatasetError(f"{path}: not a readable HDF5 data set ({err})") from err
    unknown = frozenset({"world_states"}) if attrs.get("world_states") == UNKNOWN else frozenset()
    check_step_fields(path, arrays, fields, unknown)
    check_episode_index(path, arrays, per_episode)
    check_attrs(path, attrs)
    lengths = per_episode["episode_lengths"]
    return Dataset(
        path=path,
        arrays=arrays,
        episode_starts=per_episode["episode_starts"],
        episode_lengths=lengths,
        episode_successes=per_episode["episode_successes"].astype(bool),
        attrs=attrs,
    )


def dataset_summary(dataset: Dataset) -> dict[str, Any]:
    """A JSON-ready summary: episodes, steps, success rate, field shapes, seed."""
    return {
        "path": str(dataset.path),
        "skill": dataset.skill_name,
        "episodes": dataset.num_episodes,
        "steps": dataset.num_steps,
        "success_rate": dataset.success_rate,
        "seed": int(dataset.attrs["seed"]),
        "fields": {key: list(value.shape) for key, value in dataset.arrays.items()},
    }
