"""Write project data sets as one LeRobot v3.0 data set, with pyarrow only (no lerobot).

Layout (LeRobot's ``codebase_version`` "v3.0")::

    OUT/data/chunk-000/file-<i>.parquet    one file per source data set (skill): a row per
                                           step, in episode order
    OUT/meta/info.json                     version, fps, features, path templates, totals
    OUT/meta/stats.json                    min/max/mean/std/count of every feature
    OUT/meta/tasks.parquet                 the task strings (the skill names), pandas-indexed
    OUT/meta/episodes/chunk-000/file-000.parquet   one row per episode: its task, length,
                                                   data file and row range

Features (a row is one step; ``next.*`` is what the step led to)::

    observation.state       (10,) float32  the state before the step (observations)
    action                  (7,)  float32  the action applied
    next.observation.state  (10,) float32  the state after it (next_observations)
    next.reward             float32        1 on every step at the skill's success predicate
    next.done               bool           the step reached it (terminations)
    next.truncated          bool           the step budget ended the episode (truncations)
    next.world_state        (W,)  float32  the world after it, named by ``world_fields``
    timestamp               float32        frame_index / fps, fps the domain's control rate
    frame_index, episode_index, index, task_index   int64

Every array reads back equal to its source (``lerobot_import``).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from osg_control.data.datasets import Dataset, load_dataset
from osg_control.domain.base import Domain
from osg_control.errors import DatasetError
from osg_control.io_safety import atomic_folder, refuse_package

CODEBASE_VERSION = "v3.0"
CHUNKS_SIZE = 1000
"""Files per chunk folder (LeRobot's default)."""
DATA_FILES_SIZE_IN_MB = 100
VIDEO_FILES_SIZE_IN_MB = 200
"""LeRobot's default file-size limits, recorded in ``info.json`` (no videos are written)."""
DATA_PATH = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
VIDEO_PATH = "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
EPISODES_PATH = "meta/episodes/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
INFO_FILE = "meta/info.json"
STATS_FILE = "meta/stats.json"
TASKS_FILE = "meta/tasks.parquet"
TASKS_INDEX = "__index_level_0__"
"""The column of ``tasks.parquet`` pandas restores as its index (the task strings)."""
FIELD_FEATURES: dict[str, str] = {
    "observations": "observation.state",
    "actions": "action",
    "next_observations": "next.observation.state",
    "rewards": "next.reward",
    "terminations": "next.done",
    "truncations": "next.truncated",
    "world_states": "next.world_state",
}
"""Project step field -> LeRobot feature."""
INDEX_FEATURES: dict[str, str] = {
    "timestamp": "float32",
    "frame_index": "int64",
    "episode_index": "int64",
    "index": "int64",
    "task_index": "int64",
}
"""LeRobot's per-frame bookkeeping features and their dtypes (shape (1,), stored as scalars)."""


def _dtype_name(array: np.ndarray) -> str:
    return "bool" if array.dtype == np.bool_ else str(array.dtype)


def _column(array: np.ndarray) -> pa.Array:
    """A scalar column, or a fixed-size list column for a per-step vector (LeRobot's
    ``Sequence(length=n)``)."""
    if array.ndim == 1:
        return pa.array(array)
    flat = pa.array(np.ascontiguousarray(array).reshape(-1))
    return pa.FixedSizeListArray.from_arrays(flat, array.shape[1])


def _features(data: Dataset) -> dict[str, dict[str, Any]]:
    """``info.json``'s features of a data set's rows."""
    features: dict[str, dict[str, Any]] = {}
    world_names = str(data.attrs["world_fields"]).split(",")
    for field, feature in FIELD_FEATURES.items():
        array = data.arrays[field]
        features[feature] = {
            "dtype": _dtype_name(array),
            "shape": list(array.shape[1:]) or [1],
            "names": world_names if field == "world_states" else None,
        }
    for feature, dtype in INDEX_FEATURES.items():
        features[feature] = {"dtype": dtype, "shape": [1], "names": None}
    return features


def _rows(data: Dataset, fps: float, first_episode: int, first_row: int, task: int) -> pa.Table:
    """The data file of one source data set: its steps as rows."""
    frame = np.concatenate([np.arange(n, dtype=np.int64) for n in data.episode_lengths])
    columns = {feature: _column(data.arrays[field]) for field, feature in FIELD_FEATURES.items()}
    columns["timestamp"] = pa.array((frame / fps).astype(np.float32))
    columns["frame_index"] = pa.array(frame)
    columns["episode_index"] = pa.array(data.arrays["episode_ids"] + first_episode)
    columns["index"] = pa.array(np.arange(data.num_steps, dtype=np.int64) + first_row)
    columns["task_index"] = pa.array(np.full(data.num_steps, task, dtype=np.int64))
    return pa.table(columns)


def _stats(table: pa.Table) -> dict[str, dict[str, list[float]]]:
    """LeRobot's ``stats.json``: per feature, min/max/mean/std per component and the count."""
    stats = {}
    for name in table.column_names:
        column = table.column(name).combine_chunks()
        if pa.types.is_fixed_size_list(column.type):
            values = column.flatten().to_numpy().reshape(len(column), column.type.list_size)
        else:
            values = column.to_numpy(zero_copy_only=False).reshape(-1, 1)
        values = values.astype(np.float64)
        stats[name] = {
            "min": values.min(axis=0).tolist(),
            "max": values.max(axis=0).tolist(),
            "mean": values.mean(axis=0).tolist(),
            "std": values.std(axis=0).tolist(),
            "count": [len(values)],
        }
    return stats


def _tasks_table(tasks: Sequence[str]) -> pa.Table:
    """``tasks.parquet``: ``task_index`` with the task strings as its pandas index (as
    ``DataFrame.to_parquet`` writes it, so ``pd.read_parquet`` gives LeRobot the task per
    index)."""
    table = pa.table(
        {"task_index": pa.array(range(len(tasks)), pa.int64()), TASKS_INDEX: pa.array(tasks)}
    )
    pandas_meta = {
        "index_columns": [TASKS_INDEX],
        "column_indexes": [
            {
                "name": None,
                "field_name": None,
                "pandas_type": "unicode",
                "numpy_type": "object",
                "metadata": {"encoding": "UTF-8"},
            }
        ],
        "columns": [
            {
                "name": "task_index",
                "field_name": "task_index",
                "pandas_type": "int64",
                "numpy_type": "int64",
                "metadata": None,
            },
            {
                "name": None,
                "field_name": TASKS_INDEX,
                "pandas_type": "unicode",
                "numpy_type": "object",
                "metadata": None,
            },
        ],
        "creator": {"library": "pyarrow", "version": pa.__version__},
        "pandas_version": "2.2.3",
    }
    return table.replace_schema_metadata({"pandas": json.dumps(pandas_meta)})


def _episodes_table(sources: Sequence[Dataset]) -> pa.Table:
    """``meta/episodes``: one row per episode over all sources, in order."""
    rows: dict[str, list[Any]] = {
        key: []
        for key in (
            "episode_index",
            "tasks",
            "length",
            "data/chunk_index",
            "data/file_index",
            "dataset_from_index",
            "dataset_to_index",
            "meta/episodes/chunk_index",
            "meta/episodes/file_index",
        )
    }
    row = 0
    for file, data in enumerate(sources):
        for length in data.episode_lengths:
            rows["episode_index"].append(len(rows["episode_index"]))
            rows["tasks"].append([data.skill_name])
            rows["length"].append(int(length))
            rows["data/chunk_index"].append(file // CHUNKS_SIZE)
            rows["data/file_index"].append(file % CHUNKS_SIZE)
            rows["dataset_from_index"].append(row)
            rows["dataset_to_index"].append(row + int(length))
            rows["meta/episodes/chunk_index"].append(0)
            rows["meta/episodes/file_index"].append(0)
            row += int(length)
    return pa.table(
        {
            key: pa.array(values, pa.list_(pa.string()) if key == "tasks" else pa.int64())
            for key, values in rows.items()
        }
    )


def source_files(path: Path) -> list[Path]:
    """The data set files of ``path``: itself, or the ``*.h5`` in a folder (sorted).

    Raises:
        DatasetError: a folder without data set files.
    """
    if not path.is_dir():
        return [path]
    files = sorted(path.glob("*.h5"))
    if not files:
        raise DatasetError(f"{path}: a folder without data set files (*.h5)")
    return files


def export_lerobot(
    source: str | Path, out: str | Path, domain: Domain, force: bool = False
) -> Path:
    """Write the data set file ``source`` (or every one in a folder) of ``domain`` as the
    LeRobot v3.0 data set ``out``, each skill a task, frames one control step
    (``domain.control_hz``) apart.

    Everything is built and checked (each source loaded and validated, one world-state
    layout) before the folder is written; it is written in a staging folder and moved in
    place, so a refused or failed export leaves ``out`` as it was.

    Raises:
        DatasetError: an invalid source, one recorded in another domain, sources with
            different world-state fields, an existing ``out`` without ``force``.
        OutputError: ``out`` cannot be written; names it.
    """
    out = Path(out)
    refuse_package(out)
    if out.exists() and not force:
        raise DatasetError(f"{out} exists; pass --force to replace it")
    sources = [load_dataset(path) for path in source_files(Path(source))]
    for data in sources:
        recorded = str(data.attrs.get("domain", domain.name))
        if recorded != domain.name:
            raise DatasetError(
                f"{data.path}: recorded in domain {recorded!r}, not {domain.name!r} "
                f"(pass --domain {recorded})"
            )
    fps = int(domain.control_hz) if domain.control_hz.is_integer() else domain.control_hz
    tasks = list(dict.fromkeys(data.skill_name for data in sources))
    features = _features(sources[0])
    for data in sources[1:]:
        if _features(data) != features:
            raise DatasetError(
                f"{data.path}: its features (world-state fields "
                f"{data.attrs['world_fields']!r}) differ from {sources[0].path}'s"
            )
    tables, episode, row = [], 0, 0
    for data in sources:
        tables.append(_rows(data, fps, episode, row, tasks.index(data.skill_name)))
        episode, row = episode + data.num_episodes, row + data.num_steps
    info = {
        "codebase_version": CODEBASE_VERSION,
        "robot_type": domain.name,
        "total_episodes": episode,
        "total_frames": row,
        "total_tasks": len(tasks),
        "chunks_size": CHUNKS_SIZE,
        "data_files_size_in_mb": DATA_FILES_SIZE_IN_MB,
        "video_files_size_in_mb": VIDEO_FILES_SIZE_IN_MB,
        "fps": fps,
        "splits": {"train": f"0:{episode}"},
        "data_path": DATA_PATH,
        "video_path": VIDEO_PATH,
        "features": features,
    }
    stats = _stats(pa.concat_tables(tables))

    def fill(staging: Path) -> None:
        for file, table in enumerate(tables):
            target = staging / DATA_PATH.format(
                chunk_index=file // CHUNKS_SIZE, file_index=file % CHUNKS_SIZE
            )
            target.parent.mkdir(parents=True, exist_ok=True)
            pq.write_table(table, target)
        episodes = staging / EPISODES_PATH.format(chunk_index=0, file_index=0)
        episodes.parent.mkdir(parents=True)
        pq.write_table(_episodes_table(sources), episodes)
        pq.write_table(_tasks_table(tasks), staging / TASKS_FILE)
        (staging / INFO_FILE).write_text(json.dumps(info, indent=4))
        (staging / STATS_FILE).write_text(json.dumps(stats, indent=4))

    return atomic_folder(out, fill)
