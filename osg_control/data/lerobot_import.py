"""Turn one task of a LeRobot v3.0 data set into a project data set for a skill (pyarrow).

The task string is the skill's name (as ``lerobot_export`` writes it). Features read:

- ``observation.state`` (10,) and ``action`` (7,): required, the project's state and action;
- ``next.reward``: required; a step succeeds when its reward is positive (the rewards and
  terminations are rebuilt from that, as a Minari import's ``rewards`` source);
- ``next.observation.state`` (10,): the state after each step; without it, the next
  frame's state, and each episode's last frame (which has no next state) is dropped;
- ``next.truncated``: the step budget ended the episode (default: never);
- ``next.world_state``: the world after each step, named as the domain's ``world_fields``
  (without it: unknown, NaN; such data trains a skill but gives the graph no effects).

Everything is checked before anything is written, each error naming the file and the
field: ``meta/info.json`` (a JSON object of ``codebase_version`` "v3.0", a positive
``fps``, the features above at the skill's widths), ``meta/tasks.parquet``, every data
column's width, dtype and finite values, the episodes' frame order and every action within
the domain's ``action_bounds``; ``write_episodes`` then validates the data set as every
import does. A refused import leaves the ``out`` file as it was.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from osg_control.data.datasets import Dataset, Episode
from osg_control.data.lerobot_export import (
    CODEBASE_VERSION,
    FIELD_FEATURES,
    INFO_FILE,
    TASKS_FILE,
    TASKS_INDEX,
)
from osg_control.data.minari_import import check_actions, write_import
from osg_control.data.validation import check_step_fields
from osg_control.domain.base import Domain
from osg_control.domain.spaces import ACTION_DIM, OBS_DIM
from osg_control.domain.spec import SkillSpec
from osg_control.errors import DatasetError
from osg_control.json_files import read_json_object

STATE, ACTION, NEXT_STATE, REWARD = (
    FIELD_FEATURES[k] for k in ("observations", "actions", "next_observations", "rewards")
)
TRUNCATED, WORLD = FIELD_FEATURES["truncations"], FIELD_FEATURES["world_states"]


def is_lerobot(source: str | Path) -> bool:
    """Whether ``source`` is a folder with a LeRobot ``meta/info.json``."""
    return (Path(source) / INFO_FILE).is_file()


def _widths(domain: Domain) -> dict[str, int]:
    """The width each known feature must have (1: a scalar)."""
    return {
        STATE: OBS_DIM,
        ACTION: ACTION_DIM,
        NEXT_STATE: OBS_DIM,
        REWARD: 1,
        TRUNCATED: 1,
        WORLD: len(domain.world_fields),
    }


def read_info(root: Path, domain: Domain) -> dict[str, Any]:
    """``meta/info.json``, checked: version, fps, the required features, known widths.

    Raises:
        DatasetError: the file is missing or malformed, or a feature is missing or of the
            wrong width; names the file and the field.
    """
    path = root / INFO_FILE
    info = read_json_object(path, "LeRobot info file", DatasetError)
    version = info.get("codebase_version")
    if version != CODEBASE_VERSION:
        raise DatasetError(
            f"{path}: field 'codebase_version' is {version!r}; only {CODEBASE_VERSION!r} reads"
        )
    fps = info.get("fps")
    if (
        isinstance(fps, bool)
        or not isinstance(fps, int | float)
        or not math.isfinite(fps)
        or fps <= 0
    ):
        raise DatasetError(f"{path}: field 'fps' must be a positive number, got {fps!r}")
    features = info.get("features")
    if not isinstance(features, dict):
        raise DatasetError(f"{path}: field 'features' must be a JSON object")
    for name in (STATE, ACTION, REWARD):
        if name not in features:
            raise DatasetError(f"{path}: field 'features' has no {name!r}")
    for name, width in _widths(domain).items():
        if name not in features:
            continue
        shape = features[name].get("shape") if isinstance(features[name], dict) else None
        if shape != [width]:
            raise DatasetError(
                f"{path}: feature {name!r} has shape {shape!r}, domain {domain.name!r} "
                f"needs [{width}]"
            )
    names = features.get(WORLD, {}).get("names")
    if WORLD in features and names is not None and list(names) != list(domain.world_fields):
        raise DatasetError(
            f"{path}: feature {WORLD!r} names {names!r}, not domain {domain.name!r}'s "
            f"world fields {list(domain.world_fields)!r}"
        )
    return info


def _read(path: Path, what: str) -> pa.Table:
    try:
        return pq.read_table(path)
    except (OSError, pa.ArrowException) as err:
        raise DatasetError(f"{path}: not a readable parquet {what} file ({err})") from err


def read_tasks(root: Path) -> list[str]:
    """The task strings by ``task_index`` (``meta/tasks.parquet``'s index column).

    Raises:
        DatasetError: the file is missing or unreadable, or its columns are not LeRobot's.
    """
    path = root / TASKS_FILE
    if not path.is_file():
        raise DatasetError(f"{path}: missing; the data set names no tasks")
    table = _read(path, "tasks")
    pandas_meta = json.loads((table.schema.metadata or {}).get(b"pandas", b"{}"))
    index = (pandas_meta.get("index_columns") or [TASKS_INDEX])[0]
    for column in ("task_index", index):
        if not isinstance(column, str) or column not in table.column_names:
            raise DatasetError(f"{path}: no column {column!r} (the task index and its strings)")
    order = np.argsort(table.column("task_index").to_numpy())
    return [str(table.column(index)[int(i)]) for i in order]


def _array(table: pa.Table, name: str, where: Path) -> np.ndarray:
    """One feature column as an (N,) or (N, width) array."""
    if name not in table.column_names:
        raise DatasetError(f"{where}: no column for feature {name!r}")
    column = table.column(name).combine_chunks()
    if pa.types.is_fixed_size_list(column.type):
        width = column.type.list_size
        return column.flatten().to_numpy(zero_copy_only=False).reshape(len(column), width)
    try:
        return np.asarray(column.to_pylist())
    except ValueError as err:
        raise DatasetError(f"{where}: feature {name!r} is ragged ({err})") from err


def _split(episode_ids: np.ndarray, frames: np.ndarray, where: Path) -> list[slice]:
    """The row range of each episode, checking rows run episode by episode, frame by frame."""
    starts = np.flatnonzero(np.r_[True, episode_ids[1:] != episode_ids[:-1]])
    stops = np.r_[starts[1:], len(episode_ids)]
    if len(np.unique(episode_ids)) != len(starts):
        raise DatasetError(f"{where}: field 'episode_index': an episode's rows are not together")
    for start, stop in zip(starts, stops, strict=True):
        if not np.array_equal(frames[start:stop], np.arange(stop - start)):
            raise DatasetError(
                f"{where}: field 'frame_index' of episode {int(episode_ids[start])} does not "
                "count 0, 1, 2, ... in row order"
            )
    return [slice(int(a), int(b)) for a, b in zip(starts, stops, strict=True)]


def _episodes(
    domain: Domain, table: pa.Table, features: dict[str, Any], where: Path
) -> list[Episode]:
    """The episodes of ``table`` (one task's rows), every column checked first."""
    widths = _widths(domain)
    present = [name for name in widths if name in features]
    arrays = {name: _array(table, name, where) for name in present}
    spec: dict[str, tuple[tuple[int, ...], Any]] = {
        name: ((widths[name],) if name not in (REWARD, TRUNCATED) else (), np.float32)
        for name in present
    }
    if TRUNCATED in arrays:
        spec[TRUNCATED] = ((), np.bool_)
    check_step_fields(where, arrays, spec)
    check_actions(arrays[ACTION], domain.action_bounds, str(where))
    episode_ids = _array(table, "episode_index", where)
    rows = _split(episode_ids, _array(table, "frame_index", where), where)
    steps = len(episode_ids)
    episodes = []
    for row in rows:
        if NEXT_STATE in arrays:
            take, after = row, arrays[NEXT_STATE][row]
        else:
            take = slice(row.start, row.stop - 1)
            after = arrays[STATE][row.start + 1 : row.stop]
        if take.stop <= take.start:
            continue
        success = arrays[REWARD][take] > 0
        worlds = arrays.get(WORLD, np.full((steps, len(domain.world_fields)), np.nan))
        truncated = arrays.get(TRUNCATED, np.zeros(steps, dtype=bool))
        episodes.append(
            Episode(
                observations=arrays[STATE][take].astype(np.float32),
                next_observations=after.astype(np.float32),
                actions=arrays[ACTION][take].astype(np.float32),
                rewards=success.astype(np.float32),
                terminations=success,
                truncations=truncated[take].astype(bool),
                world_states=worlds[take].astype(np.float32),
            )
        )
    return episodes


def import_lerobot(
    domain: Domain, source: str | Path, skill: str | SkillSpec, out: str | Path
) -> Dataset:
    """Convert the episodes of task ``skill`` in LeRobot data set ``source`` into the
    project data set file ``out`` (see the module docstring for what is read and checked).

    Raises:
        DatasetError: a malformed data set (the file and field named), no task of that
            name, or no episode with a next state.
    """
    skill = domain.skill(skill) if isinstance(skill, str) else skill
    root = Path(source)
    info = read_info(root, domain)
    tasks = read_tasks(root)
    if skill.name not in tasks:
        raise DatasetError(f"{root}: no task {skill.name!r} (its tasks: {', '.join(tasks)})")
    files = sorted((root / "data").glob("chunk-*/file-*.parquet"))
    if not files:
        raise DatasetError(f"{root / 'data'}: no data files (chunk-*/file-*.parquet)")
    episodes = []
    for path in files:
        table = _read(path, "data")
        rows = table.filter(pa.array(_array(table, "task_index", path) == tasks.index(skill.name)))
        if rows.num_rows:
            episodes += _episodes(domain, rows, info["features"], path)
    if not episodes:
        raise DatasetError(f"{root}: task {skill.name!r} has no episode with a next state")
    collector = f"imported from LeRobot data set {root}"
    return write_import(domain, skill, episodes, out, 0, collector, "rewards")
