"""Minari both ways: export read back by minari itself with every array equal, import into a
skill's data set (and train on it), and the bad inputs: spaces, existing folder, id."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium
import numpy as np
import pytest

from osg_control.cli import main
from osg_control.data.collect import collect_skill
from osg_control.data.datasets import Dataset
from osg_control.data.minari_export import export_minari
from osg_control.data.minari_import import import_minari
from osg_control.domain.registry import get_domain
from osg_control.errors import DatasetError
from osg_control.kitchen.env import KitchenEnv

KITCHEN = get_domain("kitchen")

minari = pytest.importorskip("minari")
pytestmark = pytest.mark.filterwarnings("ignore:.*is set to None:UserWarning")
SKILL = "move-home-to-door"
DATASET_ID = "osg/move-home-to-door-v0"


@pytest.fixture(scope="module")
def source(tmp_path_factory: pytest.TempPathFactory) -> Dataset:
    """A small collected data set (mixed successes)."""
    return collect_skill(KITCHEN, SKILL, 5, 7, tmp_path_factory.mktemp("data"), None, False)


@pytest.fixture
def root(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty Minari data-sets folder that minari reads from."""
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    return tmp_path / "minari"


def test_minari_reads_every_array_of_an_export_back(source: Dataset, root: Path) -> None:
    assert main(["datasets", "minari", str(source.path), "--id", DATASET_ID]) == 0
    loaded = minari.load_dataset(DATASET_ID)
    assert loaded.total_episodes == source.num_episodes
    assert loaded.total_steps == source.num_steps
    assert loaded.observation_space.shape == (10,) and loaded.action_space.shape == (7,)
    episodes = list(loaded.iterate_episodes())
    assert len(episodes) == source.num_episodes
    for index, episode in enumerate(episodes):
        original = source.episode(index)
        np.testing.assert_array_equal(episode.observations[:-1], original.observations)
        np.testing.assert_array_equal(episode.observations[1:], original.next_observations)
        for key in ("actions", "rewards", "terminations", "truncations"):
            np.testing.assert_array_equal(getattr(episode, key), getattr(original, key), key)
        np.testing.assert_array_equal(episode.infos["world_states"], original.world_states)
    env = loaded.recover_environment()
    assert isinstance(env.unwrapped, KitchenEnv) and env.unwrapped.skill.name == SKILL
    assert isinstance(env, gymnasium.Env) and env.spec.max_episode_steps == 200


@pytest.mark.parametrize("success", ["rewards", "predicate"])
def test_import_restores_the_data_set(
    source: Dataset, root: Path, tmp_path: Path, success: str
) -> None:
    export_minari(source.path, DATASET_ID, KITCHEN)
    back = import_minari(KITCHEN, DATASET_ID, SKILL, tmp_path / "back" / f"{SKILL}.h5", success)
    assert back.skill_name == SKILL and back.success_rate == source.success_rate
    for key, value in source.arrays.items():
        np.testing.assert_array_equal(back.arrays[key], value, err_msg=key)


def test_a_skill_trains_on_data_recorded_elsewhere(root: Path, tmp_path: Path) -> None:
    """A data set written by minari's own API (no world states) imports and trains."""
    rng = np.random.default_rng(0)
    buffers = [
        minari.data_collector.EpisodeBuffer(
            observations=rng.normal(size=(9, 10)).astype(np.float32),
            actions=rng.uniform(-0.01, 0.01, size=(8, 7)).astype(np.float32),
            rewards=np.r_[np.zeros(7), 1.0],
            terminations=np.r_[np.zeros(7, bool), True],
            truncations=np.zeros(8, bool),
        )
        for _ in range(3)
    ]
    space = gymnasium.spaces.Box(-10, 10, (10,), np.float32)
    actions = gymnasium.spaces.Box(-1, 1, (7,), np.float32)
    minari.create_dataset_from_buffers(
        "lab/home-door-v1", buffers, observation_space=space, action_space=actions
    )
    data = tmp_path / "data"
    imported = import_minari(KITCHEN, "lab/home-door-v1", SKILL, data / f"{SKILL}.h5")
    assert imported.num_episodes == 3 and imported.success_rate == 1.0
    assert np.isnan(imported.arrays["world_states"]).all()
    args = ["train", "--skill", SKILL, "--steps", "3", "--data", str(data)]
    assert main([*args, "--out", str(tmp_path / "skills"), "--threads", "1", "--json"]) == 0
    assert (tmp_path / "skills" / f"{SKILL}.safetensors").is_file()


def test_mismatched_spaces_name_both_shapes(root: Path) -> None:
    buffer = minari.data_collector.EpisodeBuffer(
        observations=np.zeros((3, 17), np.float32),
        actions=np.zeros((2, 7), np.float32),
        rewards=np.zeros(2),
        terminations=np.zeros(2, bool),
        truncations=np.array([False, True]),
    )
    minari.create_dataset_from_buffers(
        "lab/other-robot-v0",
        [buffer],
        observation_space=gymnasium.spaces.Box(-1, 1, (17,), np.float32),
        action_space=gymnasium.spaces.Box(-1, 1, (7,), np.float32),
    )
    with pytest.raises(DatasetError, match=r"shape \(17,\), but skill grab-cube needs \(10,\)"):
        import_minari(KITCHEN, "lab/other-robot-v0", "grab-cube", root / "x.h5")


def test_predicate_needs_world_states(source: Dataset, root: Path, tmp_path: Path) -> None:
    target = export_minari(source.path, DATASET_ID, KITCHEN)
    metadata = json.loads((target / "data" / "metadata.json").read_text())
    assert metadata["dataset_id"] == DATASET_ID and metadata["minari_version"] == "0.5.0"
    import h5py

    with h5py.File(target / "data" / "main_data.hdf5", "a") as f:
        del f["episode_0/infos"]
    with pytest.raises(DatasetError, match="no infos/world_states"):
        import_minari(KITCHEN, DATASET_ID, SKILL, tmp_path / "x.h5", "predicate")


def test_export_refuses_an_existing_folder_without_force(source: Dataset, root: Path) -> None:
    first = export_minari(source.path, DATASET_ID, KITCHEN)
    (first / "data" / "marker").write_text("old")
    with pytest.raises(DatasetError, match="exists; pass --force"):
        export_minari(source.path, DATASET_ID, KITCHEN)
    assert (first / "data" / "marker").exists()
    assert export_minari(source.path, DATASET_ID, KITCHEN, force=True) == first
    assert not (first / "data" / "marker").exists()


def test_malformed_id_and_missing_source_are_named(source: Dataset, root: Path) -> None:
    with pytest.raises(DatasetError, match="not NAMESPACE/NAME-vN"):
        export_minari(source.path, "no version", KITCHEN)
    with pytest.raises(DatasetError, match="no Minari data set at 'lab/none-v0'"):
        import_minari(KITCHEN, "lab/none-v0", SKILL, root / "x.h5")


def test_an_export_of_another_skill_is_not_imported_as_this_one(
    source: Dataset, root: Path, tmp_path: Path
) -> None:
    """The data set's own ``osg_skill`` names the skill it was recorded for."""
    export_minari(source.path, DATASET_ID, KITCHEN)
    out = tmp_path / "other.h5"
    with pytest.raises(DatasetError, match=f"recorded for skill '{SKILL}'.*'move-door-to-home'"):
        import_minari(KITCHEN, DATASET_ID, "move-door-to-home", out)
    assert not out.exists()


@pytest.mark.parametrize("inside", ["the folder", "its data file", "a file in it"])
def test_an_import_never_writes_into_its_source(
    inside: str, source: Dataset, root: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = export_minari(source.path, DATASET_ID, KITCHEN)
    before = {p: p.read_bytes() for p in folder.rglob("*") if p.is_file()}
    main_file = next(p for p in before if p.suffix in (".hdf5", ".h5"))
    out = {"the folder": folder, "its data file": main_file, "a file in it": folder / "x.h5"}
    argv = ["datasets", "import", str(folder), "--skill", SKILL, "--out", str(out[inside])]
    assert main(argv) == 2
    assert "is inside the source data set" in capsys.readouterr().err
    assert {p: p.read_bytes() for p in folder.rglob("*") if p.is_file()} == before
