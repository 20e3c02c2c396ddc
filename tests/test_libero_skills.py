"""The learned LIBERO pick (the ``libero`` extra; skipped without it): recording with
exploration noise is seeded, its HDF5 data round-trip and a corrupt file is named, a tiny
TD3+BC run gives a loadable checkpoint, the ``skills`` policy runs an episode from the
shipped weights, and bad command-line values exit 2."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from osg_control import cli  # noqa: E402
from osg_control.errors import CheckpointError, DatasetError  # noqa: E402
from osg_control.libero import skills  # noqa: E402
from osg_control.libero.benchmark import Job, run_job  # noqa: E402
from osg_control.libero.features import ACTION_DIM, ACTION_SCALE, OBS_DIM  # noqa: E402
from osg_control.libero.recording import (  # noqa: E402
    CollectJob,
    collect_job,
    episodes_sha256,
    pick_skill,
)
from osg_control.libero.skill_data import Recorded, load_skill_data, write_skill_data  # noqa: E402
from osg_control.libero.training import DEFAULTS_DIR, train_skill, write_skills  # noqa: E402

ATTRS = {"suite": "libero_object", "operator": "pick", "seed": 5, "noise_std": 0.005,
         "skill": pick_skill().to_json()}  # fmt: skip


def _synthetic(episodes: int = 6, seed: int = 0) -> list[Recorded]:
    """Episodes of random lifted steps, every other one successful (no simulator: the
    file format's test)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(episodes):
        steps = int(rng.integers(3, 9))
        obs = rng.normal(size=(steps + 1, OBS_DIM)).astype(np.float32)
        actions = (rng.uniform(-1, 1, (steps, ACTION_DIM)) * ACTION_SCALE).astype(np.float32)
        out.append(Recorded(list(obs[:-1]), list(actions), list(obs[1:]), i % 2 == 0, 3, 10 + i))
    return out


@pytest.mark.slow
def test_recording_is_seeded() -> None:
    """The same seed records the same pick (digest of every observation and action);
    another seed's noise records another one; the episode is the scripted pick's, in the
    lifted widths, and ends at the perceived effect."""
    job = CollectJob("libero_object", 0, (10,), "pick", 3, 0.005, 280)
    first, again = collect_job(job), collect_job(job)
    other = collect_job(CollectJob("libero_object", 0, (10,), "pick", 4, 0.005, 280))
    assert episodes_sha256(first) == episodes_sha256(again) != episodes_sha256(other)
    (episode,) = first
    assert episode.success and (episode.task, episode.init_state) == (0, 10)
    assert np.asarray(episode.observations).shape == (len(episode.actions), OBS_DIM)
    actions = np.asarray(episode.actions)
    assert np.all(np.abs(actions) <= ACTION_SCALE + 1e-6)
    assert actions[0, -1] == -1.0 and actions[-1, -1] == 1.0  # opens, then closes


def test_data_round_trip_and_a_corrupt_file_is_named(tmp_path: Path) -> None:
    episodes = _synthetic()
    path = tmp_path / "pick.h5"
    write_skill_data(path, episodes, ATTRS)
    data = load_skill_data(path)
    assert data.num_episodes == 6 and data.skill_name == "pick"
    assert list(data.episode_successes) == [True, False] * 3
    np.testing.assert_array_equal(
        data.arrays["actions"], np.concatenate([e.actions for e in episodes])
    )
    np.testing.assert_array_equal(data.attrs["episode_init_states"], np.arange(10, 16))
    assert data.arrays["rewards"].sum() == 3 and data.arrays["terminations"].sum() == 3
    with h5py.File(path, "r+") as f:  # one value changed, its checksum left as written
        f["actions"][0, 0] = 0.0123
    with pytest.raises(DatasetError, match=r"pick\.h5: field 'actions' does not match its sha256"):
        load_skill_data(path)
    path.write_bytes(b"not hdf5")
    with pytest.raises(DatasetError, match="pick.h5: not a readable HDF5"):
        load_skill_data(path)


def test_a_nan_is_refused_before_anything_is_written(tmp_path: Path) -> None:
    episodes = _synthetic()
    episodes[1].observations[0][2] = np.nan
    with pytest.raises(DatasetError, match="non-finite"):
        write_skill_data(tmp_path / "pick.h5", episodes, ATTRS)
    assert not any(tmp_path.iterdir())


def test_tiny_training_gives_a_loadable_checkpoint(tmp_path: Path) -> None:
    path = tmp_path / "pick.h5"
    write_skill_data(path, _synthetic(), ATTRS)
    checkpoint, log = train_skill([load_skill_data(path)], steps=20, seed=1)
    write_skills(tmp_path / "skills_dir", checkpoint, [load_skill_data(path)], "test", log)
    (policy,) = skills.load_skills(tmp_path / "skills_dir").values()
    action = policy(np.zeros(OBS_DIM, dtype=np.float32))
    assert action.shape == (ACTION_DIM,) and np.all(np.abs(action) <= ACTION_SCALE + 1e-6)
    again, _ = train_skill([load_skill_data(path)], steps=20, seed=1)
    for (w1, b1), (w2, b2) in zip(checkpoint.layers, again.layers, strict=True):
        np.testing.assert_array_equal(w1, w2)
        np.testing.assert_array_equal(b1, b2)
    manifest = json.loads((tmp_path / "skills_dir" / "manifest.json").read_text())
    assert manifest["skills"]["pick"]["operators"] == ["pick", "pick-out"]
    (data,) = manifest["skills"]["pick"]["data"]
    assert data["tasks"] == [3] and data["init_states"] == list(range(10, 16))
    weights = tmp_path / "skills_dir" / "skills" / "pick.safetensors"
    weights.write_bytes(weights.read_bytes()[:-4] + b"\0\0\0\0")
    with pytest.raises(CheckpointError, match=r"pick\.safetensors: weights do not match"):
        skills.load_skills(tmp_path / "skills_dir")


def test_the_skills_policy_runs_an_episode_from_the_shipped_weights() -> None:
    """LIBERO-Object task 0, initial state 0 (not trained on: the data are states 10-29):
    the plan runs, its pick-out by the learned network, perceived done, and the task is
    scored a success by the env."""
    assert skills.shipped()
    job = Job("libero_object", 0, (0,), skills.skills_factory(DEFAULTS_DIR), 280, 0)
    (episode,) = run_job(job)
    picks = [line for line in episode.trace if " pick-out " in line]
    assert picks == [picks[0]] and picks[0].endswith(
        "alphabet_soup_1 floor_target_object_region: ok"
    )
    assert episode.success and len(episode.actions_sha256) == 64


@pytest.mark.slow
def test_the_shipped_pick_takes_both_moka_pots_by_the_knob() -> None:
    """LIBERO-10 task 8, initial state 2 (not trained on: the data are states 10-19): the
    network takes each moka pot by its lid knob at the first try and the task succeeds
    (the weights recorded on handle grasps ran out their 150 steps over the first knob)."""
    job = Job("libero_10", 8, (2,), skills.skills_factory(DEFAULTS_DIR), 520, 0)
    (episode,) = run_job(job)
    picks = [line for line in episode.trace if " pick moka_pot_" in line]
    assert len(picks) == 2 and all(line.endswith(": ok") for line in picks), episode.trace
    assert episode.success


def test_the_shipped_rate_is_measured_on_states_the_data_never_used() -> None:
    """The shipped manifest's ``success_rates`` come from held-out initial states: no
    (suite, initial state) of its measurement is one its data were recorded on."""
    manifest = json.loads((DEFAULTS_DIR / "manifest.json").read_text())
    pick = manifest["skills"]["pick"]
    trained = {(d["suite"], s) for d in pick["data"] for s in d["init_states"]}
    rate = manifest["measured"]["pick"]
    measured = {(e["suite"], s) for e in rate["episodes"]
                for states in e["tasks"].values() for s in states}  # fmt: skip
    assert measured and trained and not measured & trained
    assert manifest["success_rates"]["pick"] == round(rate["perceived_successes"] / rate["runs"], 4)


def test_the_benchmark_names_a_corrupt_skills_folder(tmp_path: Path, capsys) -> None:
    shutil.copytree(DEFAULTS_DIR, tmp_path / "models")
    (tmp_path / "models" / "skills" / "pick.json").write_text("{")
    argv = ["--domain", "libero", "evaluate", "benchmark", "--suite", "libero_object",
            "--task", "0", "--episodes", "1", "--models", str(tmp_path / "models")]  # fmt: skip
    assert cli.main(argv) == 1
    assert "pick.json" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv,named",
    [
        (["collect", "--suite", "libero_object", "--init-states", "0:2", "--operator", "place",
          "--out", "x.h5"], "--operator"),
        (["collect", "--suite", "libero_object", "--init-states", "0:51", "--operator", "pick",
          "--out", "x.h5"], "0:51"),
        (["collect", "--suite", "libero_object", "--init-states", "0:2", "--operator", "pick",
          "--out", "x.txt"], "--out"),
        (["collect", "--suite", "libero_object", "--init-states", "0:2", "--operator", "pick",
          "--out", str(DEFAULTS_DIR / "x.h5")], "inside the installed package"),
        (["collect", "--suite", "libero_object", "--init-states", "0:2", "--operator", "pick",
          "--out", "x.h5", "--noise", "-1"], "--noise"),
        (["collect", "--suite", "libero_object", "--task", "10", "--init-states", "0:2",
          "--operator", "pick", "--out", "x.h5"], "10"),
        (["train", "--data", "x.h5", "--out", "d", "--steps", "0"], "--steps"),
        (["train", "--data", "x.csv", "--out", "d"], "--data"),
        (["train", "--data", "x.h5", "--out", "d", "--seed", "-1"], "--seed"),
        (["evaluate", "benchmark", "--suite", "libero_10", "--policy", "scripted-plan",
          "--models", "d"], "--models"),
    ],
)  # fmt: skip
def test_bad_input_exits_2_naming_it(argv: list[str], named: str, capsys, tmp_path: Path,
                                     monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    monkeypatch.chdir(tmp_path)
    assert cli.main(["--domain", "libero", *argv]) == 2
    assert named in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_without_shipped_skills_the_benchmark_refuses(monkeypatch: pytest.MonkeyPatch,
                                                      capsys) -> None:  # fmt: skip
    monkeypatch.setattr(skills, "shipped", lambda: False)
    argv = ["--domain", "libero", "evaluate", "benchmark", "--suite", "libero_10", "--task", "0"]
    assert cli.main(argv) == 1
    assert "no learned LIBERO skills shipped" in capsys.readouterr().err


def test_operator_outcomes_count_the_traced_effects() -> None:
    from osg_control.libero.benchmark import Episode, operator_outcomes

    trace = (
        "0 plan (solved): 5 steps", "30 approach bowl_1: ok", "58 pick bowl_1 plate_1: FAILED",
        "90 plan (solved): 4 steps", "120 pick bowl_1 plate_1: ok", "learned pick: stopped (x)",
    )  # fmt: skip
    episode = Episode(0, 0, False, 200, 0.0, 0.0, trace)
    assert operator_outcomes([episode, episode]) == {
        "approach": {"runs": 2, "ok": 2}, "pick": {"runs": 4, "ok": 2}
    }  # fmt: skip
