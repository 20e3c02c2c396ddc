"""LeRobot v3.0 both ways: a round trip of two skills with every array equal, the written
files against the layout's documented fields, and bad input refused with nothing written."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from osg_control.cli import main
from osg_control.data.collect import collect_skill
from osg_control.data.datasets import load_dataset
from osg_control.domain.registry import get_domain

KITCHEN = get_domain("kitchen")
SKILLS = ("move-home-to-door", "grab-handle")

DOCUMENTED_INFO_KEYS = (
    "codebase_version",
    "robot_type",
    "total_episodes",
    "total_frames",
    "total_tasks",
    "chunks_size",
    "data_files_size_in_mb",
    "video_files_size_in_mb",
    "fps",
    "splits",
    "data_path",
    "video_path",
    "features",
)
"""``meta/info.json``'s keys in LeRobot's v3.0 data sets (as the Hub's data-set cards show
them, e.g. huggingface.co/datasets/aero1201/my_custom_pusht)."""
DOCUMENTED_DATA_PATH = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
DOCUMENTED_DEFAULT_FEATURES = {
    "timestamp": "float32",
    "frame_index": "int64",
    "episode_index": "int64",
    "index": "int64",
    "task_index": "int64",
}
"""The features every LeRobot frame carries, each of shape [1]. (These lists restate the
layout on purpose: the test checks the writer against the documentation, not itself.)"""
DOCUMENTED_EPISODE_COLUMNS = (
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
"""``meta/episodes/chunk-000/file-000.parquet``'s columns that LeRobotDataset reads
(../shared/notes/perception-and-ecosystem.md, measured with lerobot)."""


@pytest.fixture(scope="module")
def sources(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder of two small collected data sets."""
    folder = tmp_path_factory.mktemp("data")
    for seed, skill in enumerate(SKILLS):
        collect_skill(KITCHEN, skill, 3, seed, folder, None, False)
    return folder


@pytest.fixture(scope="module")
def exported(sources: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("lerobot") / "kitchen"
    assert main(["datasets", "lerobot", str(sources), "--out", str(out)]) == 0
    return out


def test_a_round_trip_gives_every_array_back(sources: Path, exported: Path, tmp_path: Path) -> None:
    for skill in SKILLS:
        out = tmp_path / f"{skill}.h5"
        args = ["datasets", "import", str(exported), "--layout", "lerobot", "--skill", skill]
        assert main([*args, "--out", str(out)]) == 0
        source, back = load_dataset(sources / f"{skill}.h5"), load_dataset(out)
        assert back.skill_name == skill and back.num_episodes == source.num_episodes
        assert source.num_steps > 0 and set(back.arrays) == set(source.arrays)
        for key, value in source.arrays.items():
            np.testing.assert_array_equal(back.arrays[key], value, err_msg=key)
        np.testing.assert_array_equal(back.episode_successes, source.episode_successes)


def test_the_files_carry_the_documented_v3_fields(sources: Path, exported: Path) -> None:
    info = json.loads((exported / "meta" / "info.json").read_text())
    assert set(DOCUMENTED_INFO_KEYS) <= set(info)
    assert info["codebase_version"] == "v3.0" and info["data_path"] == DOCUMENTED_DATA_PATH
    steps = sum(load_dataset(sources / f"{s}.h5").num_steps for s in SKILLS)
    episodes = sum(load_dataset(sources / f"{s}.h5").num_episodes for s in SKILLS)
    assert info["total_frames"] == steps and info["total_episodes"] == episodes
    assert info["total_tasks"] == 2 and info["splits"] == {"train": f"0:{episodes}"}
    assert info["fps"] == KITCHEN.control_hz
    for name, dtype in DOCUMENTED_DEFAULT_FEATURES.items():
        assert info["features"][name]["dtype"] == dtype and info["features"][name]["shape"] == [1]
    assert info["features"]["observation.state"]["shape"] == [10]
    assert info["features"]["action"]["shape"] == [7]

    table = pa.concat_tables(
        pq.read_table(exported / DOCUMENTED_DATA_PATH.format(chunk_index=0, file_index=i))
        for i in range(2)
    )
    assert set(table.column_names) == set(info["features"])
    assert table.num_rows == steps
    np.testing.assert_array_equal(table.column("index").to_numpy(), np.arange(steps))
    frames = table.column("frame_index").to_numpy()
    np.testing.assert_allclose(
        table.column("timestamp").to_numpy(), frames / KITCHEN.control_hz, rtol=1e-6
    )
    assert pa.types.is_fixed_size_list(table.schema.field("observation.state").type)

    meta = pq.read_table(exported / "meta" / "episodes" / "chunk-000" / "file-000.parquet")
    assert set(DOCUMENTED_EPISODE_COLUMNS) <= set(meta.column_names)
    rows = meta.to_pylist()
    assert [r["episode_index"] for r in rows] == list(range(episodes))
    for row in rows:
        span = table.slice(row["dataset_from_index"], row["length"])
        assert set(span.column("episode_index").to_pylist()) == {row["episode_index"]}
        assert row["dataset_to_index"] - row["dataset_from_index"] == row["length"]

    tasks = pq.read_table(exported / "meta" / "tasks.parquet")
    pandas_meta = json.loads(tasks.schema.metadata[b"pandas"])
    index = pandas_meta["index_columns"][0]
    named = dict(
        zip(tasks.column(index).to_pylist(), tasks.column("task_index").to_pylist(), strict=True)
    )
    assert set(named) == set(SKILLS)
    first = {
        r["task_index"]
        for r in table.filter(pa.compute.equal(table["episode_index"], 0)).to_pylist()
    }
    assert first == {named[rows[0]["tasks"][0]]}

    stats = json.loads((exported / "meta" / "stats.json").read_text())
    assert set(stats) == set(info["features"])
    state = np.stack(table.column("observation.state").to_numpy(zero_copy_only=False))
    np.testing.assert_allclose(stats["observation.state"]["mean"], state.mean(axis=0), rtol=1e-5)
    for values in stats.values():
        assert {"min", "max", "mean", "std", "count"} <= set(values)


def test_tasks_read_back_through_pandas_as_lerobot_reads_them(exported: Path) -> None:
    pandas = pytest.importorskip("pandas", reason="pandas reads tasks.parquet's index")
    tasks = pandas.read_parquet(exported / "meta" / "tasks.parquet")
    assert sorted(tasks.index) == sorted(SKILLS)
    assert tasks.loc[SKILLS[0], "task_index"] in (0, 1)


def _refused(folder: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    """Import ``folder`` over an existing file; assert exit 1 and the file untouched."""
    out = tmp_path / "kept.h5"
    out.write_bytes(b"old")
    args = ["datasets", "import", str(folder), "--layout", "lerobot", "--skill", SKILLS[0]]
    assert main([*args, "--out", str(out)]) == 1
    assert out.read_bytes() == b"old"
    assert not (tmp_path / "new.h5").exists()
    return capsys.readouterr().err


@pytest.fixture
def copy(exported: Path, tmp_path: Path) -> Path:
    target = tmp_path / "copy"
    shutil.copytree(exported, target)
    return target


def _edit_info(folder: Path, edit) -> None:
    path = folder / "meta" / "info.json"
    info = json.loads(path.read_text())
    edit(info)
    path.write_text(json.dumps(info))


def test_a_missing_or_malformed_info_is_named(
    copy: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (copy / "meta" / "info.json").write_text('{"codebase_version": "v3.0", "fps": ')
    assert "info.json: corrupt LeRobot info file" in _refused(copy, tmp_path, capsys)
    (copy / "meta" / "info.json").write_text("[1, 2]")
    assert "corrupt LeRobot info file (not a JSON object)" in _refused(copy, tmp_path, capsys)
    (copy / "meta" / "info.json").write_text('{"codebase_version": "v2.1", "fps": 20}')
    assert "field 'codebase_version' is 'v2.1'" in _refused(copy, tmp_path, capsys)
    (copy / "meta" / "info.json").write_text('{"codebase_version": "v3.0", "fps": 20}')
    assert "field 'features' must be a JSON object" in _refused(copy, tmp_path, capsys)
    (copy / "meta" / "info.json").unlink()
    assert "info.json: LeRobot info file not found" in _refused(copy, tmp_path, capsys)


def test_a_feature_of_the_wrong_width_is_named(
    copy: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _edit_info(copy, lambda info: info["features"]["action"].update(shape=[6]))
    assert "feature 'action' has shape [6]" in _refused(copy, tmp_path, capsys)
    _edit_info(copy, lambda info: info["features"]["action"].update(shape=[7]))
    for data in (copy / "data" / "chunk-000").glob("*.parquet"):
        table = pq.read_table(data)
        state = np.stack(table.column("observation.state").to_numpy(zero_copy_only=False))
        narrow = pa.FixedSizeListArray.from_arrays(pa.array(state[:, :9].reshape(-1)), 9)
        pq.write_table(table.set_column(0, "observation.state", narrow), data)
    err = _refused(copy, tmp_path, capsys)
    assert "field 'observation.state' has shape" in err and "expected (N, 10)" in err


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_non_finite_values_are_named(
    copy: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], value: float
) -> None:
    for file in (copy / "data" / "chunk-000").glob("*.parquet"):
        table = pq.read_table(file)
        actions = np.stack(table.column("action").to_numpy(zero_copy_only=False))
        actions[2, 1] = value
        column = pa.FixedSizeListArray.from_arrays(pa.array(actions.reshape(-1)), 7)
        index = table.column_names.index("action")
        pq.write_table(table.set_column(index, "action", column), file)
    assert "field 'action' has a non-finite value at step 2" in _refused(copy, tmp_path, capsys)


def test_bad_command_lines_exit_2_and_an_unknown_task_is_named(
    exported: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "x.h5"
    assert main(["datasets", "import", str(exported), "--out", str(out)]) == 2
    assert "--skill is required" in capsys.readouterr().err
    args = ["datasets", "import", str(exported), "--skill", "grab-cube", "--out", str(out)]
    assert main(args) == 1
    assert "no task 'grab-cube'" in capsys.readouterr().err and not out.exists()


def test_an_existing_export_needs_force(sources: Path, exported: Path) -> None:
    assert main(["datasets", "lerobot", str(sources), "--out", str(exported)]) == 1
    assert main(["datasets", "lerobot", str(sources), "--out", str(exported), "--force"]) == 0
    assert json.loads((exported / "meta" / "info.json").read_text())["total_tasks"] == 2


def test_data_without_next_states_or_worlds_imports_from_the_next_frames(
    sources: Path, copy: Path, tmp_path: Path
) -> None:
    """A LeRobot data set of another origin: no next state, world or truncation features."""
    dropped = ("next.observation.state", "next.world_state", "next.truncated")
    _edit_info(copy, lambda info: [info["features"].pop(name) for name in dropped])
    for file in (copy / "data" / "chunk-000").glob("*.parquet"):
        pq.write_table(pq.read_table(file).drop_columns(list(dropped)), file)
    out = tmp_path / "imported.h5"
    args = ["datasets", "import", str(copy), "--skill", SKILLS[0], "--out", str(out)]
    assert main(args) == 0
    source, back = load_dataset(sources / f"{SKILLS[0]}.h5"), load_dataset(out)
    np.testing.assert_array_equal(back.episode_lengths, source.episode_lengths - 1)
    assert back.attrs["world_states"] == "unknown" and np.isnan(back.arrays["world_states"]).all()
    assert not back.arrays["truncations"].any()
    for index in range(source.num_episodes):
        original, imported = source.episode(index), back.episode(index)
        np.testing.assert_array_equal(imported.observations, original.observations[:-1])
        np.testing.assert_array_equal(imported.next_observations, original.observations[1:])
        np.testing.assert_array_equal(imported.actions, original.actions[:-1])
        np.testing.assert_array_equal(imported.rewards, original.rewards[:-1])
