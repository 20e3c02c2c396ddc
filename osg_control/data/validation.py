"""Validation of a data set's fields: dtypes, shapes, finite values and the episode index.

``load_dataset`` runs these checks on what it read and ``write_episodes`` on what it is
about to write, so a data set that would train into garbage (one NaN in ``rewards``, a
success flag that disagrees with the rewards, an episode index that does not tile the
steps) is refused with a ``DatasetError`` naming the file and the field, before any
training and before an existing file is replaced.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from osg_control.errors import DatasetError
from osg_control.json_files import parse_json

PER_EPISODE_KINDS = {
    "episode_starts": ("iu", "integer"),
    "episode_lengths": ("iu", "integer"),
    "episode_successes": ("b", "bool"),
}


def _kind_ok(array: np.ndarray, dtype: Any) -> bool:
    """Whether ``array`` has the kind of ``dtype`` (float, bool or integer)."""
    want = np.dtype(dtype).kind
    return array.dtype.kind in ("iu" if want in "iu" else want)


def check_step_fields(
    path: Path | str,
    arrays: Mapping[str, np.ndarray],
    spec: Mapping[str, tuple[tuple[int, ...], Any]],
    unknown: frozenset[str] = frozenset(),
) -> int:
    """Shapes, dtypes and finiteness of the flat step arrays; returns the step count N.

    ``unknown``: fields a file declares unrecorded (e.g. world states of an imported data
    set): they must then be NaN throughout instead of finite. ``path`` names the arrays'
    source in messages (a file, or a file and an episode group).

    Raises:
        DatasetError: naming the file and the first bad field.
    """
    steps = None
    for key, (shape, dtype) in spec.items():
        array = arrays[key]
        if array.ndim != 1 + len(shape) or array.shape[1:] != shape:
            expected = ", ".join(["N", *map(str, shape)])
            raise DatasetError(
                f"{path}: field {key!r} has shape {array.shape}, expected ({expected})"
            )
        if not _kind_ok(array, dtype):
            raise DatasetError(
                f"{path}: field {key!r} has dtype {array.dtype}, expected {np.dtype(dtype)}"
            )
        if key in unknown:
            if not np.all(np.isnan(array)):
                raise DatasetError(f"{path}: field {key!r} is declared unknown but has values")
        elif array.dtype.kind == "f" and not np.all(np.isfinite(array)):
            bad = int(np.flatnonzero(~np.isfinite(array).reshape(len(array), -1).all(axis=1))[0])
            raise DatasetError(f"{path}: field {key!r} has a non-finite value at step {bad}")
        if steps is not None and len(array) != steps:
            raise DatasetError(f"{path}: field {key!r} has {len(array)} steps, others {steps}")
        steps = len(array)
    return int(steps or 0)


def check_episode_index(
    path: Path, arrays: Mapping[str, np.ndarray], per_episode: Mapping[str, np.ndarray]
) -> None:
    """The per-episode arrays tile the steps and agree with the step arrays.

    Lengths >= 1 that add up to N, starts at their running offsets, ``episode_ids`` the
    episode of each step, rewards 0 or 1 with ``terminations`` exactly the rewarded steps,
    and each success flag true exactly when its episode has a reward.

    Raises:
        DatasetError: naming the file and the field that disagrees.
    """
    for key, (kinds, kind_name) in PER_EPISODE_KINDS.items():
        value = per_episode[key]
        if value.ndim != 1 or value.dtype.kind not in kinds:
            raise DatasetError(
                f"{path}: field {key!r} must be a 1-D {kind_name} array, got "
                f"shape {value.shape} dtype {value.dtype}"
            )
    lengths, starts = per_episode["episode_lengths"], per_episode["episode_starts"]
    successes = per_episode["episode_successes"]
    if not len(lengths) == len(starts) == len(successes):
        raise DatasetError(
            f"{path}: episode_starts, episode_lengths and episode_successes differ in length "
            f"({len(starts)}, {len(lengths)}, {len(successes)})"
        )
    steps = len(arrays["actions"])
    if np.any(lengths < 1) or int(lengths.sum()) != steps:
        raise DatasetError(
            f"{path}: field 'episode_lengths' must be >= 1 and add up to the {steps} steps"
        )
    offsets = np.cumsum(lengths) - lengths
    if not np.array_equal(starts, offsets):
        raise DatasetError(
            f"{path}: field 'episode_starts' is not the running sum of 'episode_lengths'"
        )
    if not np.array_equal(arrays["episode_ids"], np.repeat(np.arange(len(lengths)), lengths)):
        raise DatasetError(f"{path}: field 'episode_ids' does not match episode_lengths")
    rewards = arrays["rewards"]
    if not np.all((rewards == 0.0) | (rewards == 1.0)):
        raise DatasetError(f"{path}: field 'rewards' has values other than 0 and 1")
    if not np.array_equal(arrays["terminations"], rewards > 0):
        raise DatasetError(f"{path}: field 'terminations' disagrees with the rewarded steps")
    rewarded = np.add.reduceat(rewards, offsets) > 0 if steps else np.zeros(0, dtype=bool)
    if not np.array_equal(successes, rewarded):
        raise DatasetError(
            f"{path}: field 'episode_successes' disagrees with the episodes' rewards"
        )


def check_attrs(path: Path, attrs: Mapping[str, Any]) -> None:
    """``skill`` is a JSON skill spec with a name and ``seed`` a non-negative integer.

    Raises:
        DatasetError: naming the file and the attribute.
    """
    for key in ("skill", "seed"):
        if key not in attrs:
            raise DatasetError(f"{path}: missing attribute {key!r}")
    try:
        skill = parse_json(attrs["skill"])
        if not isinstance(skill, dict) or not isinstance(skill.get("name"), str):
            raise ValueError("no skill name")
    except (TypeError, ValueError) as err:
        raise DatasetError(f"{path}: attribute 'skill' is not a JSON skill spec ({err})") from err
    seed = attrs["seed"]
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or int(seed) < 0:
        raise DatasetError(f"{path}: attribute 'seed' must be a non-negative integer, got {seed!r}")


def check_within(
    values: np.ndarray, low: Any, high: Any, where: str, field: str, what: str
) -> None:
    """Refuse the first entry of a (T, n) array outside ``[low, high]`` (per column).

    Raises:
        DatasetError: ``<where>: field '<field>' at step t, component c: v is outside
        <what> [low, high]``.
    """
    low = np.broadcast_to(np.asarray(low, dtype=float), values.shape[1:])
    high = np.broadcast_to(np.asarray(high, dtype=float), values.shape[1:])
    outside = np.argwhere((values < low) | (values > high))
    if len(outside):
        step, column = (int(i) for i in outside[0])
        raise DatasetError(
            f"{where}: field {field!r} at step {step}, component {column}: "
            f"{float(values[step, column])!r} is outside {what} "
            f"[{float(low[column]):g}, {float(high[column]):g}]"
        )
