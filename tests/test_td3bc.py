"""TD3+BC: learning a toy reaching task, batching, determinism, data checks, ``osg train``."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import torch

from osg_control.cli import main
from osg_control.data.datasets import Episode, load_dataset, write_episodes
from osg_control.errors import DatasetError
from osg_control.kitchen.domain import kitchen_domain
from osg_control.kitchen.skills import get_skill
from osg_control.kitchen.world import WORLD_FIELDS
from osg_control.learning.checkpoints import Checkpoint, normalise_observations
from osg_control.learning.policy import SkillPolicy, load_policies
from osg_control.learning.replay import BatchedReplay, SkillData, prepare_skill_data
from osg_control.learning.td3bc import TD3BC, TD3BCConfig, bc_weights
from osg_control.seeding import skill_seed

WORLD = ",".join(WORLD_FIELDS)
ACTION_SCALE = np.asarray(kitchen_domain().action_bounds, dtype=np.float32)
"""The kitchen's action bounds: what its data are scaled by in training."""

SKILL = "move-home-to-cube"
OTHER_SKILL = "move-cube-to-home"
GOAL = np.array([0.50, -0.20, 0.15])
"""Goal position of the toy reaching task [m]."""
TOLERANCE = 0.015
"""Distance to GOAL at which a toy episode succeeds [m]."""
TOY_STEPS = 40
"""Step budget of a toy episode."""
START_DISTANCE = (0.10, 0.25)
"""Range of a toy episode's initial distance to GOAL [m] (5 to 13 steps of demonstration)."""
SMALL = TD3BCConfig(hidden_sizes=(64, 64), batch_size=64)
"""Networks small enough for fast tests."""


def toy_obs(positions: np.ndarray) -> np.ndarray:
    """10-D observations of a point-mass TCP at ``positions`` (N, 3), top-down, gripper open."""
    obs = np.zeros((len(positions), 10), dtype=np.float32)
    obs[:, :3] = positions
    obs[:, 3:7] = (0.0, 1.0, 0.0, 0.0)
    obs[:, 9] = 0.08
    return obs


def toy_episode(rng: np.random.Generator, noise: float) -> Episode:
    """A noisy demonstration: per-axis steps of at most 0.02 m toward GOAL, noise std ``noise``.

    The angles and gripper components are pure noise; they do not change the state.
    """
    direction = rng.normal(size=3)
    position = GOAL + direction / np.linalg.norm(direction) * rng.uniform(*START_DISTANCE)
    positions, actions, rewards = [position], [], []
    for _ in range(TOY_STEPS):
        action = rng.normal(0.0, [noise] * 3 + [0.03] * 3 + [0.2])
        action[:3] += GOAL - position
        action = np.clip(action, -ACTION_SCALE, ACTION_SCALE)
        position = position + action[:3]
        positions.append(position)
        actions.append(action)
        rewards.append(float(np.linalg.norm(GOAL - position) < TOLERANCE))
        if rewards[-1]:
            break
    steps = len(actions)
    terminations = np.array(rewards, dtype=bool)
    return Episode(
        observations=toy_obs(np.array(positions[:-1])),
        next_observations=toy_obs(np.array(positions[1:])),
        actions=np.array(actions, dtype=np.float32),
        rewards=np.array(rewards, dtype=np.float32),
        terminations=terminations,
        truncations=~terminations & (np.arange(steps) == steps - 1),
        world_states=np.zeros((steps, 11), dtype=np.float32),
    )


def write_toy_dataset(
    path: Path, skill: str = SKILL, episodes: int = 100, seed: int = 0, noise: float = 0.006
) -> Path:
    """Write ``episodes`` toy demonstrations recorded as skill ``skill`` to ``path``."""
    rng = np.random.default_rng(seed)
    attrs = {"skill": get_skill(skill).to_json(), "seed": seed, "world_fields": WORLD}
    write_episodes(path, [toy_episode(rng, noise) for _ in range(episodes)], attrs)
    return path


@pytest.fixture(autouse=True)
def one_thread() -> Iterator[None]:
    """Tiny networks on a shared 2-core machine: a second thread costs more than it saves."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def toy_data(tmp_path: Path, skill: str = SKILL, seed: int = 0) -> SkillData:
    """A toy data set written, loaded and prepared for training."""
    path = write_toy_dataset(tmp_path / f"{skill}-{seed}.h5", skill, seed=seed)
    return prepare_skill_data(load_dataset(path), ACTION_SCALE)


def train(
    data: list[SkillData], seeds: list[int], steps: int, config: TD3BCConfig = SMALL
) -> TD3BC:
    """Train the given skills batched for ``steps`` updates."""
    replay = BatchedReplay(data, config.batch_size, seeds)
    trainer = TD3BC(config, seeds)
    for _ in range(steps):
        trainer.train_step(replay.sample())
    return trainer


def actor_arrays(trainer: TD3BC, skill: int) -> list[np.ndarray]:
    return [array for layer in trainer.actor_layers(skill) for array in layer]


@pytest.mark.slow
def test_learns_to_move_toward_goal_from_noisy_demos(tmp_path: Path) -> None:
    data = toy_data(tmp_path)
    trainer = train([data], [1], steps=4000)
    rng = np.random.default_rng(123)
    offsets = rng.normal(size=(200, 3))
    distances = rng.uniform(0.03, START_DISTANCE[1], (200, 1))
    offsets *= distances / np.linalg.norm(offsets, axis=1, keepdims=True)
    expert = np.clip(-offsets, -ACTION_SCALE[:3], ACTION_SCALE[:3])  # the noise-free demo
    obs = normalise_observations(toy_obs(GOAL + offsets), data.obs_mean, data.obs_std)
    actions = trainer.actions(torch.as_tensor(obs)[None])[0, :, :3].numpy()
    norms = np.linalg.norm(actions, axis=1) * np.linalg.norm(expert, axis=1)
    cosine = np.sum(actions * expert, axis=1) / norms
    assert np.median(cosine) > 0.95 and np.quantile(cosine, 0.1) > 0.7, cosine

    # Closed loop, through the run-time policy made from the trainer's actor.
    checkpoint = toy_checkpoint(trainer, data, steps=4000, seed=1)
    policy = SkillPolicy(checkpoint)
    positions, reached = GOAL + offsets, np.zeros(len(offsets), dtype=bool)
    for _ in range(TOY_STEPS):
        positions = positions + policy(toy_obs(positions))[:, :3]
        reached |= np.linalg.norm(positions - GOAL, axis=1) < TOLERANCE
    assert reached.mean() >= 0.9, reached.mean()


def test_batched_training_matches_training_alone(tmp_path: Path) -> None:
    a, b = toy_data(tmp_path, SKILL, seed=1), toy_data(tmp_path, OTHER_SKILL, seed=2)
    both = train([a, b], [11, 22], steps=40)
    for k, alone in enumerate((train([a], [11], steps=40), train([b], [22], steps=40))):
        for batched, single in zip(actor_arrays(both, k), actor_arrays(alone, 0), strict=True):
            # Not bit-exact: with one skill, MKL evaluates the width-1 critic output layer as
            # a matrix-vector product, which sums in another order (differences ~1e-8).
            np.testing.assert_allclose(batched, single, rtol=0, atol=1e-5)


def test_same_seed_same_weights_and_other_seed_differs(tmp_path: Path) -> None:
    data = toy_data(tmp_path)
    first, second = train([data], [5], steps=20), train([data], [5], steps=20)
    other = train([data], [6], steps=20)
    for x, y, z in zip(
        actor_arrays(first, 0), actor_arrays(second, 0), actor_arrays(other, 0), strict=True
    ):
        assert np.array_equal(x, y)
        assert not np.array_equal(x, z)
    assert skill_seed(0, SKILL) == skill_seed(0, SKILL)
    assert len({skill_seed(0, SKILL), skill_seed(1, SKILL), skill_seed(0, OTHER_SKILL)}) == 3


def test_actor_and_targets_update_every_policy_freq_steps(tmp_path: Path) -> None:
    data = toy_data(tmp_path)
    replay = BatchedReplay([data], SMALL.batch_size, [0])
    trainer = TD3BC(SMALL, [0])

    def unchanged() -> list[bool]:
        now = trainer.actor + trainer.critic_target
        return [torch.equal(p, q) for p, q in zip(initial, now, strict=True)]

    initial = [p.detach().clone() for p in trainer.actor + trainer.critic_target]
    first = trainer.train_step(replay.sample())
    assert set(first) == {"critic_loss", "q_mean"}
    assert all(unchanged())
    second = trainer.train_step(replay.sample())
    assert {"actor_loss", "bc_loss", "lam"} <= set(second)
    assert all(value.shape == (1,) and torch.isfinite(value).all() for value in second.values())
    assert not any(unchanged())


def test_data_set_without_success_is_refused(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    failures = [
        dataclasses.replace(
            episode,
            rewards=np.zeros_like(episode.rewards),
            terminations=np.zeros_like(episode.terminations),
        )
        for episode in (toy_episode(rng, 0.006) for _ in range(5))
    ]
    path = tmp_path / f"{SKILL}.h5"
    write_episodes(
        path, failures, {"skill": get_skill(SKILL).to_json(), "seed": 0, "world_fields": WORLD}
    )
    with pytest.raises(DatasetError, match="no successful episode") as info:
        prepare_skill_data(load_dataset(path), ACTION_SCALE)
    assert str(path) in str(info.value)


def test_action_beyond_its_bound_is_refused(tmp_path: Path) -> None:
    dataset = load_dataset(write_toy_dataset(tmp_path / "toy.h5"))
    with pytest.raises(DatasetError, match="action dimension 0") as info:
        prepare_skill_data(dataset, ACTION_SCALE * np.array([0.5, 1, 1, 1, 1, 1, 1]))
    assert str(dataset.path) in str(info.value)


def test_train_command_writes_loadable_checkpoints(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data_dir, out_dir = tmp_path / "data", tmp_path / "skills"
    write_toy_dataset(data_dir / f"{SKILL}.h5")
    argv = ["train", "--skill", SKILL, "--steps", "4", "--seed", "3", "--data", str(data_dir)]
    assert main([*argv, "--out", str(out_dir), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["steps"] == 4 and summary["skills"][0]["skill"] == SKILL
    assert Path(summary["skills"][0]["weights"]) == out_dir / f"{SKILL}.safetensors"
    policy = load_policies(out_dir)[SKILL]
    assert policy.checkpoint.steps == 4 and policy.checkpoint.seed == 3
    assert policy(np.zeros(10, dtype=np.float32)).shape == (7,)
    assert sorted(p.name for p in out_dir.iterdir()) == [f"{SKILL}.json", f"{SKILL}.safetensors"]


def test_train_command_names_unknown_skills_and_missing_data(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["train", "--skill", "fly", "--data", str(tmp_path)]) == 1
    assert "known skills: move-home-to-cube" in capsys.readouterr().err
    assert main(["train", "--skill", SKILL, "--data", str(tmp_path)]) == 1
    assert str(tmp_path / f"{SKILL}.h5") in capsys.readouterr().err


def test_train_command_refuses_data_recorded_for_another_skill(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    write_toy_dataset(tmp_path / f"{SKILL}.h5", skill=OTHER_SKILL)
    assert main(["train", "--skill", SKILL, "--data", str(tmp_path)]) == 1
    assert f"recorded for skill {OTHER_SKILL!r}" in capsys.readouterr().err


def toy_checkpoint(trainer: TD3BC, data: SkillData, steps: int, seed: int) -> Checkpoint:
    """A checkpoint of skill 0 of ``trainer`` trained on the toy data."""
    return Checkpoint(
        skill=get_skill(SKILL),
        layers=trainer.actor_layers(0),
        obs_mean=data.obs_mean,
        obs_std=data.obs_std,
        action_scale=data.action_scale,
        train_config=SMALL.to_json_dict(),
        steps=steps,
        seed=seed,
        dataset_sha256="ab" * 32,
    )


def test_bc_weights_single_out_gripper_switches() -> None:
    actions = torch.tensor(
        [[0.3, -0.2, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0] * 6 + [-1.0], [0.0] * 6 + [1.0]]
    )
    weights = bc_weights(actions, 10.0)
    expected = torch.ones_like(actions)
    expected[1:, -1] = 10.0
    torch.testing.assert_close(weights, expected)
    torch.testing.assert_close(bc_weights(actions, 1.0), torch.ones_like(actions))


def test_observation_noise_perturbs_only_the_tcp_position(tmp_path: Path) -> None:
    """``obs_noise`` adds seeded Gaussian noise of that std [m] to the TCP position of the
    sampled observations and next observations and to nothing else; the batch indices and
    smoothing noise are those of a replay without it, and 0 draws nothing."""
    data = [toy_data(tmp_path), toy_data(tmp_path, OTHER_SKILL, seed=1)]
    seeds = [3, 4]
    sigma = 0.02
    plain, zero = BatchedReplay(data, 4096, seeds), BatchedReplay(data, 4096, seeds, obs_noise=0.0)
    noisy, again = (BatchedReplay(data, 4096, seeds, obs_noise=sigma) for _ in range(2))
    for _ in range(2):  # the second draw too: the streams stay aligned
        p, z, n, a = plain.sample(), zero.sample(), noisy.sample(), again.sample()
        for field in dataclasses.fields(p):
            assert torch.equal(getattr(p, field.name), getattr(z, field.name))
            assert torch.equal(getattr(n, field.name), getattr(a, field.name))  # seeded
        for field in ("actions", "rewards", "dones", "noise"):
            assert torch.equal(getattr(p, field), getattr(n, field))
        for key in ("observations", "next_observations"):
            diff = (getattr(n, key) - getattr(p, key)).numpy()
            assert not diff[..., 3:].any()
            for k, skill in enumerate(data):
                metres = diff[k, :, :3] * skill.obs_std[:3]  # back to physical units
                assert np.allclose(metres.std(0), sigma, rtol=0.06)
                assert np.allclose(metres.mean(0), 0.0, atol=0.002)
        drawn = n.observations - p.observations
        assert not torch.equal(drawn, n.next_observations - p.next_observations)  # independent


def test_observation_noise_per_skill_leaves_a_noiseless_skill_as_without_noise(
    tmp_path: Path,
) -> None:
    """One noise per skill (``Domain.recipe``): a skill with none samples exactly what it
    samples with none for every skill, one with some exactly what it samples with that for
    every skill."""
    data = [toy_data(tmp_path), toy_data(tmp_path, OTHER_SKILL, seed=1)]
    seeds, sigma = [3, 4], 0.02
    plain, noisy = BatchedReplay(data, 512, seeds), BatchedReplay(data, 512, seeds, obs_noise=sigma)
    mixed = BatchedReplay(data, 512, seeds, obs_noise=[0.0, sigma])
    for _ in range(2):
        p, n, m = plain.sample(), noisy.sample(), mixed.sample()
        for field in dataclasses.fields(p):
            assert torch.equal(getattr(m, field.name)[0], getattr(p, field.name)[0])
            assert torch.equal(getattr(m, field.name)[1], getattr(n, field.name)[1])
    with pytest.raises(ValueError, match="one obs_noise per skill"):
        BatchedReplay(data, 8, seeds, obs_noise=[0.01])


@pytest.mark.parametrize("bad", [-0.01, float("nan"), float("inf"), [0.0, -0.01]])
def test_observation_noise_must_be_a_finite_std(tmp_path: Path, bad: float | list[float]) -> None:
    with pytest.raises(ValueError, match="obs_noise"):
        data = toy_data(tmp_path)
        BatchedReplay([data, data], 8, [0, 1], obs_noise=bad)
