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
``domain``. Each of the arrays carries a ``sha256`` attribute, the hash of its bytes,
checked on load (a flipped bit is a ``DatasetError``); a file stores it on every array or
on none (files written before the checksums load unchecked; an array stripped of its
checksum beside checksummed siblings is a ``DatasetError``).
"""

from __future__ import annotations

import hashlib
import io
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from osg_control.data.validation import (
    PER_EPISODE_KINDS,
    check_attrs,
    check_episode_index,
    check_step_fields,
)
from osg_control.domain.spaces import ACTION_DIM, OBS_DIM
from osg_control.errors import DatasetError
from osg_control.io_safety import atomic_write
from osg_control.json_files import parse_json

FORMAT_VERSION = 1
UNKNOWN = "unknown"
"""``world_states`` attribute of a data set whose world states were not recorded (all NaN,
e.g. imported from elsewhere): it trains a skill, but yields no effects for the graph."""
WORLD_WIDTH = -1
"""Stands for the domain's world-state width in ``STEP_FIELDS`` (fixed per file)."""
CHECKSUM_ATTR = "sha256"
"""Attribute of every HDF5 data set of a data set file: the sha256 of the array's bytes,
written at save and verified at load (files without any, from before, load unchecked)."""
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
        return str(parse_json(self.attrs["skill"])["name"])

    def episode(self, index: int) -> Episode:
        """Slice out one episode."""
        start = int(self.episode_starts[index])
        stop = start + int(self.episode_lengths[index])
        return Episode(
            **{key: self.arrays[key][start:stop] for key in STEP_FIELDS if key != "episode_ids"}
        )


def _field_spec(world_width: int) -> dict[str, tuple[tuple[int, ...], Any]]:
    """``STEP_FIELDS`` with the world-state width filled in."""
    return {
        key: ((world_width,), dtype) if shape == (WORLD_WIDTH,) else (shape, dtype)
        for key, (shape, dtype) in STEP_FIELDS.items()
    }


def _unknown_fields(attrs: dict[str, Any]) -> frozenset[str]:
    """The fields a file's attributes declare unrecorded (all NaN): world states or none."""
    return frozenset({"world_states"}) if attrs.get("world_states") == UNKNOWN else frozenset()


FILE_OVERHEAD = 16 * 2**10
"""Bytes a data set file takes beyond its arrays: HDF5 headers and attributes (measured
about 10 kB)."""


def dataset_bytes(steps: int, episodes: int, world_width: int) -> int:
    """The bytes a data set file of ``steps`` steps in ``episodes`` episodes takes on disk
    (its arrays plus ``FILE_OVERHEAD``)."""
    per_step = sum(
        np.dtype(dtype).itemsize * int(np.prod(shape))
        for shape, dtype in _field_spec(world_width).values()
    )
    return steps * per_step + episodes * (8 + 8 + 1) + FILE_OVERHEAD


def content_sha256(array: np.ndarray) -> str:
    """The sha256 of an array's bytes (C order): the ``CHECKSUM_ATTR`` of its HDF5 data set."""
    return hashlib.sha256(np.ascontiguousarray(array).tobytes()).hexdigest()


def _arrays(
    episodes: Sequence[Episode], world_width: int
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The flat step arrays and the per-episode arrays of ``episodes``, as they are stored."""
    lengths = np.array([len(e) for e in episodes], dtype=np.int64)
    arrays = {}
    for key, (shape, dtype) in _field_spec(world_width).items():
        if key == "episode_ids":
            values = np.repeat(np.arange(len(episodes), dtype=np.int64), lengths)
        elif episodes:
            values = np.concatenate([getattr(e, key) for e in episodes]).astype(dtype)
        else:
            values = np.zeros((0, *shape), dtype=dtype)
        arrays[key] = values.reshape((-1, *shape))
    per_episode = {
        "episode_starts": (np.cumsum(lengths) - lengths).astype(np.int64),
        "episode_lengths": lengths,
        "episode_successes": np.array([e.success for e in episodes], dtype=np.bool_),
    }
    return arrays, per_episode


def write_episodes(path: Path, episodes: Sequence[Episode], attrs: dict[str, Any]) -> None:
    """Validate episodes in memory, then write them to ``path`` atomically.

    Every field is checked as ``load_dataset`` checks it before anything is written, so a
    refused write leaves an existing ``path`` byte-identical; an interrupted write leaves
    the old file (or none), never a truncated one. Each HDF5 data set gets the sha256 of
    its bytes (``CHECKSUM_ATTR``), verified on load.

    Raises:
        DatasetError: a field that ``load_dataset`` would refuse, naming ``path`` and it.
        OutputError: the file cannot be written (a full disk, a read-only folder); names it.
    """
    world_width = _world_width(attrs, path)
    arrays, per_episode = _arrays(episodes, world_width)
    check_step_fields(path, arrays, _field_spec(world_width), _unknown_fields(attrs))
    check_episode_index(path, arrays, per_episode)

    def fill(f: h5py.File) -> None:
        for key, values in {**arrays, **per_episode}.items():
            f.create_dataset(key, data=values).attrs[CHECKSUM_ATTR] = content_sha256(values)
        f.attrs["format_version"] = FORMAT_VERSION
        for key, value in attrs.items():
            f.attrs[key] = value

    data = hdf5_bytes(fill)
    atomic_write(path, lambda tmp: tmp.write_bytes(data))


def hdf5_bytes(fill: Callable[[h5py.File], object], **options: Any) -> bytes:
    """The bytes of an HDF5 file built in memory by ``fill(file)`` (``options`` go to
    ``h5py.File``, e.g. ``track_order``).

    Written with one plain ``write_bytes``, a full disk is an ordinary ``OSError`` (named
    by ``atomic_write``); h5py writing to a full disk fails in its close, keeps the file
    open, prints tracebacks when the objects are freed and crashes the interpreter at exit.
    """
    buffer = io.BytesIO()
    with h5py.File(buffer, "w", **options) as f:
        fill(f)
    return buffer.getvalue()


def read_field(f: h5py.File, key: str, path: Path, checked: bool) -> np.ndarray:
    """Read data set ``key``, checking its content sha256; ``checked``: whether the file
    stores checksums (then every field must carry one).

    Raises:
        DatasetError: the field is missing, lacks its checksum in a checksummed file, or
            its bytes differ from the checksum written with them (the file is corrupt);
            names the file and the field.
    """
    if key not in f:
        raise DatasetError(f"{path}: missing field {key!r}")
    array = np.asarray(f[key][()])
    stored = f[key].attrs.get(CHECKSUM_ATTR)
    if stored is None and checked:
        raise DatasetError(
            f"{path}: field {key!r} lacks its sha256 content checksum while other fields "
            "carry theirs: the file was altered (re-collect or re-import it)"
        )
    if stored is not None and stored != content_sha256(array):
        raise DatasetError(
            f"{path}: field {key!r} does not match its sha256 content checksum: the file is "
            "corrupt (re-collect or re-import it)"
        )
    return array


def _world_width(attrs: Mapping[str, Any], path: Path) -> int:
    """The world-state width a file's attributes declare (``world_fields``, the
    comma-separated world-state names).

    Raises:
        DatasetError: the attribute is missing or empty; names the file.
    """
    fields = attrs.get("world_fields")
    if not isinstance(fields, str) or not fields:
        raise DatasetError(f"{path}: missing attribute 'world_fields' (the world-state names)")
    return len(fields.split(","))


def load_dataset(path: str | Path, require_checksums: bool = False) -> Dataset:
    """Read and validate a data set file. A file stores a checksum on every array or on
    none (written before the checksums); ``require_checksums``: refuse the latter too
    (a resumed collection chunk, always written by this version).

    Raises:
        DatasetError: naming the file and what is wrong (missing, not HDF5, missing field,
            a missing or wrong checksum, wrong shape or dtype, non-finite values, an
            inconsistent episode index; see ``osg_control.data.validation``).
    """
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f"{path}: data set file not found")
    try:
        with h5py.File(path, "r") as f:
            keys = [*STEP_FIELDS, *PER_EPISODE_KINDS]
            checked = require_checksums or any(
                CHECKSUM_ATTR in f[key].attrs for key in keys if key in f
            )
            arrays = {key: read_field(f, key, path, checked) for key in STEP_FIELDS}
            per_episode = {key: read_field(f, key, path, checked) for key in PER_EPISODE_KINDS}
            attrs = dict(f.attrs)
            fields = _field_spec(_world_width(f.attrs, path))
    except DatasetError:
        raise
    except (OSError, KeyError, ValueError, TypeError) as err:
        raise DatasetError(f"{path}: not a readable HDF5 data set ({err})") from err
    check_step_fields(path, arrays, fields, _unknown_fields(attrs))
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
