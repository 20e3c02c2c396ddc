"""The D4RL kitchen human data (Minari layout) into franka-kitchen skills, on a synthetic file.

The real ``D4RL/kitchen/*-v2`` data cannot be downloaded here, so a module fixture writes a
small data set in that layout with minari's own writer: three episodes of 40 steps whose
joints, fingers and object qpos are made up (microwave then kettle; one episode with
per-step completion infos naming a task no skill does; one that starts with the light on).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import gymnasium
import h5py
import numpy as np
import pytest

from osg_control.cli import main
from osg_control.control.rotations import quat_to_matrix, rotation_step
from osg_control.data.datasets import load_dataset
from osg_control.domain.registry import get_domain
from osg_control.errors import DatasetError, UsageError
from osg_control.franka.d4rl_import import import_d4rl
from osg_control.franka.envs import make_franka_env
from osg_control.pipeline.train import train_skills

minari = pytest.importorskip("minari")
gymnasium_robotics = pytest.importorskip("gymnasium_robotics")
from gymnasium_robotics.envs.franka_kitchen.kitchen_env import (  # noqa: E402
    OBS_ELEMENT_GOALS,
    OBS_ELEMENT_INDICES,
)

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")
FRANKA = get_domain("franka-kitchen")
DATASET_ID = "D4RL/kitchen/synthetic-v2"
STEPS = 40
TASKS = ("microwave", "kettle", "light switch")
"""The goal tasks the file lists (as kitchen-mixed lists four; the others are read from the
observed object qpos)."""
CLOSE_STEP, OPEN_STEP, JUMP_STEP = 10, 25, 3
"""Steps at which the made-up teleoperator closes and opens the hand, and jerks joint 1."""
HANDLE_WIDTH = 0.02
"""Each finger's joint on the handle (the fingers stop there when closed)."""


def _row(obs_index: int) -> int:
    """The observation column of a qpos index (the object qpos start at column 18)."""
    return 18 + obs_index - 9


def _episode(reset: np.ndarray, rng: np.random.Generator, kind: str) -> dict[str, Any]:
    """A made-up episode: smooth joint motion, a grasp, the microwave then the kettle (with
    ``kind`` "slide" the slide cabinet opened between them, not a goal task of the file;
    "light": the light switch done from the start, the microwave only)."""
    actions = np.zeros((STEPS, 9))
    actions[:, :7] = 0.2 * np.sin(np.linspace(0, 3, STEPS)[:, None] + np.arange(7))
    actions[JUMP_STEP, 0] = 0.999
    actions[CLOSE_STEP, 7:] = -0.4
    actions[OPEN_STEP, 7:] = 0.4
    obs = np.repeat(reset[None], STEPS + 1, axis=0)
    obs[1:, :7] = reset[:7] + np.cumsum(actions[:, :7] * 2 * 0.08 * 0.7, axis=0)
    obs[CLOSE_STEP + 1 : OPEN_STEP + 1, 7:9] = HANDLE_WIDTH
    obs[:, 9:18] = 0.0
    obs[:, :9] += rng.uniform(-1e-3, 1e-3, (STEPS + 1, 9))
    micro = _row(OBS_ELEMENT_INDICES["microwave"][0])
    obs[:, micro] = np.interp(np.arange(STEPS + 1), [12, 22], [0.0, -0.8])
    kettle_y = _row(OBS_ELEMENT_INDICES["kettle"][1])
    if kind != "light":
        obs[:, kettle_y] = np.interp(np.arange(STEPS + 1), [28, 36], [reset[kettle_y], 0.75])
    else:
        for index, goal in zip(
            OBS_ELEMENT_INDICES["light switch"], OBS_ELEMENT_GOALS["light switch"], strict=True
        ):
            obs[:, _row(index)] = goal
    if kind == "slide":
        slide = _row(OBS_ELEMENT_INDICES["slide cabinet"][0])
        obs[:, slide] = np.interp(np.arange(STEPS + 1), [23, 27], [0.0, 0.3])
    achieved = {t: obs[:, [_row(i) for i in OBS_ELEMENT_INDICES[t]]] for t in TASKS}
    desired = {t: np.repeat(OBS_ELEMENT_GOALS[t][None], STEPS + 1, axis=0) for t in TASKS}
    return {
        "observations": {"observation": obs, "achieved_goal": achieved, "desired_goal": desired},
        "actions": actions.astype(np.float32),
        "rewards": np.zeros(STEPS),
        "terminations": np.zeros(STEPS, bool),
        "truncations": np.r_[np.zeros(STEPS - 1, bool), True],
        "infos": {"ctrl": np.zeros((STEPS, 9))},
    }


def _completion(episode: dict[str, Any], task: str) -> int:
    """The step after which the library's rule first holds for ``task``."""
    goals = episode["observations"]
    distance = np.linalg.norm(goals["achieved_goal"][task] - goals["desired_goal"][task], axis=1)
    return int(np.flatnonzero(distance < 0.3)[0]) - 1


@pytest.fixture(scope="module")
def made() -> dict[str, Any]:
    """The env's reset observation and the three synthetic episodes (as written)."""
    adapter = make_franka_env()
    obs, _ = adapter.env.reset(seed=0)
    adapter.close()
    rng = np.random.default_rng(0)
    episodes = [_episode(obs["observation"], rng, k) for k in ("slide", "flags", "light")]
    flags = {task: np.zeros(STEPS, bool) for task in ("microwave", "toaster", "kettle")}
    for task, step in (("microwave", 15), ("toaster", 20), ("kettle", 30)):
        flags[task][step] = True
    episodes[1]["infos"]["step_task_completions"] = flags
    return {"episodes": episodes}


@pytest.fixture
def source(made: dict[str, Any], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The synthetic data set, written by minari itself; returns its data folder."""
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    box = lambda n: gymnasium.spaces.Box(-np.inf, np.inf, (n,), np.float64)  # noqa: E731
    goals = gymnasium.spaces.Dict({t: box(len(OBS_ELEMENT_GOALS[t])) for t in TASKS})
    space = gymnasium.spaces.Dict(
        {"observation": box(59), "achieved_goal": goals, "desired_goal": goals}
    )
    buffers = [minari.data_collector.EpisodeBuffer(**e) for e in made["episodes"]]
    minari.create_dataset_from_buffers(
        DATASET_ID,
        buffers,
        observation_space=space,
        action_space=gymnasium.spaces.Box(-1, 1, (9,), np.float32),
    )
    return tmp_path / "minari" / DATASET_ID / "data"


def test_episodes_are_cut_at_the_completions(
    made: dict[str, Any], source: Path, tmp_path: Path
) -> None:
    summary = import_d4rl(FRANKA, DATASET_ID, tmp_path / "out")
    assert sorted(summary.skills) == ["pull-microwave", "push-kettle", "push-slide"]
    episodes = {name: row["episodes"] for name, row in summary.skills.items()}
    assert episodes == {"pull-microwave": 3, "push-kettle": 2, "push-slide": 1}
    assert summary.skipped_tasks == {"toaster": 1} and summary.done_at_start == {"light switch": 1}
    assert summary.completions_from == {"goals": 2, "infos": 1}
    first = made["episodes"][0]
    micro, kettle = _completion(first, "microwave"), _completion(first, "kettle")
    slide = 23  # the observed slide door passes 0.07 m (the rule's 0.3 of 0.37) at row 24
    assert micro < slide < kettle
    files = {n: load_dataset(tmp_path / "out" / f"{n}.h5") for n in summary.skills}
    assert all(d.skill_name == n and d.success_rate == 1.0 for n, d in files.items())
    # episode 0 by the goals (and the observed slide), episode 1 by its infos (microwave at
    # 15, toaster at 20: dropped, kettle at 30), episode 2 by the goals
    assert files["pull-microwave"].episode_lengths.tolist() == [micro + 1, 16, micro + 1]
    assert files["push-slide"].episode_lengths.tolist() == [slide - micro]
    assert files["push-kettle"].episode_lengths.tolist() == [kettle - slide, 30 - 20]
    for dataset in files.values():
        rewarded = np.flatnonzero(dataset.arrays["rewards"])
        ends = dataset.episode_starts + dataset.episode_lengths - 1
        assert rewarded.tolist() == ends.tolist()
        assert np.array_equal(dataset.arrays["terminations"], dataset.arrays["rewards"] > 0)
    tails = (STEPS - 1 - kettle) + (STEPS - 1 - 30) + (STEPS - 1 - micro)
    assert summary.dropped_steps == tails + (20 - 15)  # and the toaster's steps 16-20


def test_states_are_the_env_percept_and_actions_in_bounds(
    made: dict[str, Any], source: Path, tmp_path: Path
) -> None:
    summary = import_d4rl(FRANKA, source.parent, tmp_path / "out")
    pull = load_dataset(tmp_path / "out" / "pull-microwave.h5").episode(0)
    obs = made["episodes"][0]["observations"]["observation"]
    steps = len(pull)
    adapter = make_franka_env()
    try:
        for t in range(steps + 1):
            state = pull.observations[t] if t < steps else pull.next_observations[-1]
            position, _rotation = adapter.ik.tcp_pose(obs[t, :7])
            np.testing.assert_allclose(state[:3], position, atol=1e-6)
            closed = CLOSE_STEP < t <= OPEN_STEP
            assert state[7] == (-1.0 if closed else 1.0), t
            assert state[8] == pytest.approx(
                adapter.robot.gripper.kp * obs[t, 7:9].min() if closed else 0.0, abs=1e-4
            )
            assert state[9] == pytest.approx(obs[t, 7:9].sum(), abs=1e-6)
    finally:
        adapter.close()
    bounds = np.asarray(FRANKA.action_bounds, dtype=np.float32)
    actions = pull.actions
    assert np.all(np.abs(actions) <= bounds)
    assert summary.scaled_actions >= 3  # the jerk at JUMP_STEP, in each episode
    assert np.abs(actions[JUMP_STEP, :3]).max() == pytest.approx(0.04)
    moved = pull.next_observations[:, :3] - pull.observations[:, :3]
    free = np.abs(moved).max(axis=1) < 0.04
    free[JUMP_STEP] = False
    np.testing.assert_allclose(actions[free, :3], moved[free], atol=2e-6)
    for t in np.flatnonzero(free):  # the rotation vector turns state t's TCP into t+1's
        turned = rotation_step(quat_to_matrix(pull.observations[t, 3:7]), actions[t, 3:6])
        np.testing.assert_allclose(
            turned, quat_to_matrix(pull.next_observations[t, 3:7]), atol=1e-5
        )
    gripper = np.zeros(steps)
    gripper[CLOSE_STEP] = -1.0
    np.testing.assert_array_equal(actions[:, 6], gripper)
    assert np.isfinite(pull.world_states).all()


def _corrupt(source: Path, change: str) -> None:
    """Damage episode 1 of the source in place."""
    with h5py.File(source / "main_data.hdf5", "a") as f:
        group = f["episode_1"]
        if change in ("nan", "joint"):
            values = group["observations/observation"][()]
            values[5, 3] = np.nan if change == "nan" else 1e30
            group["observations/observation"][...] = values
        elif change == "shape":
            del group["actions"]
            group["actions"] = np.zeros((STEPS, 8), np.float32)
        elif change == "missing":
            del group["rewards"]
        else:
            del group["observations/desired_goal/kettle"]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ("nan", r"episode_1: field 'observations/observation' has a non-finite value at step 5"),
        ("joint", r"episode_1: field 'observations/observation' at step 5, component 3: 1e\+30"),
        ("shape", r"episode_1: field 'actions' has shape \(40, 8\), expected \(N, 9\)"),
        ("missing", r"episode_1: missing field 'rewards'"),
        ("goal", r"episode_1: missing field 'observations/desired_goal/kettle'"),
    ],
)
def test_a_corrupt_source_is_refused_and_the_folder_kept(
    source: Path, tmp_path: Path, change: str, message: str
) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "pull-microwave.h5").write_bytes(b"old")
    _corrupt(source, change)
    with pytest.raises(DatasetError, match=message):
        import_d4rl(FRANKA, DATASET_ID, out)
    assert [p.name for p in out.iterdir()] == ["pull-microwave.h5"]
    assert (out / "pull-microwave.h5").read_bytes() == b"old"


def test_cli_imports_with_json_and_refuses_other_domains(
    source: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    args = ["datasets", "import", DATASET_ID, "--out", str(out)]
    assert main(["--domain", "franka-kitchen", *args, "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["skills"]["push-kettle"]["episodes"] == 2
    assert summary["skipped_tasks"] == {"toaster": 1}
    assert main(["--domain", "franka-kitchen", *args]) == 0
    assert "pull-microwave (microwave), 3 episodes" in capsys.readouterr().out
    assert main(args) == 2  # the default domain, the MuJoCo kitchen, has no d4rl layout
    assert "--skill is required for a project-layout" in capsys.readouterr().err
    assert main([*args, "--layout", "d4rl"]) == 2
    assert "domain 'kitchen' imports no 'd4rl' layout" in capsys.readouterr().err
    assert main(["--domain", "franka-kitchen", *args, "--skill", "push-kettle"]) == 2
    shutil.rmtree(out)
    _corrupt(source, "nan")
    assert main(["--domain", "franka-kitchen", *args, "--layout", "d4rl"]) == 1
    assert "non-finite value at step 5" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.slow
def test_the_imported_skills_train(source: Path, tmp_path: Path) -> None:
    import_d4rl(FRANKA, DATASET_ID, tmp_path / "data")
    trained = train_skills(
        FRANKA,
        tmp_path / "data",
        tmp_path / "skills",
        ["pull-microwave", "push-kettle"],
        steps=20,
        threads=1,
    )
    assert [row["skill"] for row in trained.skills] == ["pull-microwave", "push-kettle"]
    assert (tmp_path / "skills" / "push-kettle.safetensors").is_file()


def test_a_usage_error_names_the_domain(source: Path, tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="--domain kitchen"):
        import_d4rl(get_domain("kitchen"), DATASET_ID, tmp_path / "out")


def test_a_project_layout_source_still_takes_the_one_skill_import(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--layout auto`` leaves a 10-D/7-D Minari data set to the one-skill importer."""
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    buffer = minari.data_collector.EpisodeBuffer(
        observations=np.zeros((4, 10), np.float32),
        actions=np.zeros((3, 7), np.float32),
        rewards=np.array([0.0, 0.0, 1.0]),
        terminations=np.array([False, False, True]),
        truncations=np.zeros(3, bool),
    )
    minari.create_dataset_from_buffers(
        "lab/kettle-v0",
        [buffer],
        observation_space=gymnasium.spaces.Box(-10, 10, (10,), np.float32),
        action_space=gymnasium.spaces.Box(-1, 1, (7,), np.float32),
    )
    args = ["--domain", "franka-kitchen", "datasets", "import", "lab/kettle-v0"]
    out = tmp_path / "push-kettle.h5"
    assert main([*args, "--out", str(out)]) == 2  # no --skill
    assert main([*args, "--out", str(out), "--skill", "push-kettle"]) == 0
    assert load_dataset(out).skill_name == "push-kettle"
