"""Checkpoints and SkillPolicy: round trip, file format, corruption and mismatch refusals."""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import torch
from safetensors.numpy import load_file
from test_td3bc import OTHER_SKILL, SKILL, SMALL, toy_checkpoint, toy_data, train

from osg_control import __version__
from osg_control.errors import CheckpointError
from osg_control.kitchen.skills import get_skill
from osg_control.learning.checkpoints import (
    OBS_CLIP,
    checkpoint_paths,
    load_checkpoint,
    normalise_observations,
    save_checkpoint,
    sha256_file,
)
from osg_control.learning.policy import SkillPolicy, load_policies
from osg_control.learning.replay import SkillData
from osg_control.learning.td3bc import TD3BC


@pytest.fixture(scope="module")
def trained_once(tmp_path_factory: pytest.TempPathFactory) -> tuple[TD3BC, SkillData, Path]:
    """A toy skill trained for a few updates and saved, once for the module."""
    root = tmp_path_factory.mktemp("trained")
    data = toy_data(root)
    trainer = train([data], [7], steps=10)
    checkpoint = toy_checkpoint(trainer, data, steps=10, seed=7)
    save_checkpoint(root / "skills", checkpoint)
    return trainer, data, root / "skills"


@pytest.fixture
def trained(
    tmp_path: Path, trained_once: tuple[TD3BC, SkillData, Path]
) -> tuple[TD3BC, SkillData, Path]:
    """The trained toy skill, its data, and a private copy of its checkpoint directory."""
    trainer, data, directory = trained_once
    return trainer, data, Path(shutil.copytree(directory, tmp_path / "skills"))


def test_policy_reproduces_the_torch_actor(trained: tuple[TD3BC, SkillData, Path]) -> None:
    trainer, data, directory = trained
    policy = SkillPolicy.load(directory, SKILL)
    obs = np.random.default_rng(0).normal(size=(32, 10)).astype(np.float32)
    obs[:, :3] = obs[:, :3] * 0.1 + np.array([0.5, -0.2, 0.15], dtype=np.float32)
    normalised = torch.as_tensor(normalise_observations(obs, data.obs_mean, data.obs_std))
    expected = trainer.actions(normalised[None])[0].numpy() * data.action_scale
    batch = policy(obs)
    assert batch.shape == (32, 7) and batch.dtype == np.float32
    np.testing.assert_allclose(batch, expected, rtol=0, atol=1e-6)
    np.testing.assert_allclose(policy(obs[3]), batch[3], rtol=1e-5, atol=1e-7)
    assert np.all(np.abs(batch) <= data.action_scale)


def test_files_are_safetensors_and_a_complete_sidecar(
    trained: tuple[TD3BC, SkillData, Path],
) -> None:
    _, data, directory = trained
    weights_path, sidecar_path = checkpoint_paths(directory, SKILL)
    assert sorted(p.name for p in directory.iterdir()) == [sidecar_path.name, weights_path.name]
    tensors = load_file(weights_path)
    assert tensors["layers.0.weight"].shape == (10, 64)
    assert tensors["layers.2.bias"].shape == (7,)
    sidecar = json.loads(sidecar_path.read_text())
    assert (sidecar["obs_dim"], sidecar["action_dim"], sidecar["hidden_sizes"]) == (10, 7, [64, 64])
    assert sidecar["obs_std"] == pytest.approx(data.obs_std.tolist())
    assert sidecar["skill_spec"] == json.loads(get_skill(SKILL).to_json())
    assert sidecar["train_config"]["batch_size"] == SMALL.batch_size
    assert (sidecar["steps"], sidecar["seed"]) == (10, 7)
    assert sidecar["weights_sha256"] == sha256_file(weights_path)
    assert sidecar["package_version"] == __version__
    loaded = load_checkpoint(directory, SKILL)
    recorded = dataclasses.replace(get_skill(SKILL), parameters=())  # as spec.to_json records it
    assert loaded.skill == recorded and loaded.dataset_sha256 == "ab" * 32


@pytest.mark.parametrize("which", ["weights", "sidecar"])
def test_missing_file_is_named(trained: tuple[TD3BC, SkillData, Path], which: str) -> None:
    _, _, directory = trained
    weights_path, sidecar_path = checkpoint_paths(directory, SKILL)
    path = weights_path if which == "weights" else sidecar_path
    path.unlink()
    with pytest.raises(CheckpointError, match="not found") as info:
        load_checkpoint(directory, SKILL)
    assert str(path) in str(info.value)


def test_corrupt_weights_are_named(trained: tuple[TD3BC, SkillData, Path]) -> None:
    _, _, directory = trained
    weights_path, sidecar_path = checkpoint_paths(directory, SKILL)
    weights_path.write_bytes(weights_path.read_bytes()[:100])
    with pytest.raises(CheckpointError, match="weights_sha256") as info:
        load_checkpoint(directory, SKILL)
    assert str(weights_path) in str(info.value)

    # Garbage whose hash the sidecar agrees with still fails to parse.
    sidecar = json.loads(sidecar_path.read_text())
    sidecar["weights_sha256"] = sha256_file(weights_path)
    sidecar_path.write_text(json.dumps(sidecar))
    with pytest.raises(CheckpointError, match="corrupt safetensors") as info:
        load_checkpoint(directory, SKILL)
    assert str(weights_path) in str(info.value)


def test_corrupt_sidecar_is_named(trained: tuple[TD3BC, SkillData, Path]) -> None:
    _, _, directory = trained
    _, sidecar_path = checkpoint_paths(directory, SKILL)
    sidecar_path.write_text(sidecar_path.read_text()[:-20])
    with pytest.raises(CheckpointError, match="corrupt checkpoint sidecar") as info:
        load_checkpoint(directory, SKILL)
    assert str(sidecar_path) in str(info.value)


def test_dimension_mismatch_names_both_shapes(trained: tuple[TD3BC, SkillData, Path]) -> None:
    _, _, directory = trained
    with pytest.raises(CheckpointError, match=r"\(10, 7\), expected \(12, 7\)"):
        load_checkpoint(directory, SKILL, obs_dim=12)
    with pytest.raises(CheckpointError, match=r"\(10, 7\), expected \(10, 6\)"):
        SkillPolicy.load(directory, SKILL, action_dim=6)


def test_checkpoint_of_another_skill_names_both(trained: tuple[TD3BC, SkillData, Path]) -> None:
    _, _, directory = trained
    for source, target in zip(
        checkpoint_paths(directory, SKILL), checkpoint_paths(directory, OTHER_SKILL), strict=True
    ):
        source.rename(target)
    with pytest.raises(CheckpointError, match=f"for skill '{SKILL}'.*'{OTHER_SKILL}'"):
        load_checkpoint(directory, OTHER_SKILL)


def test_policy_validates_observations(trained: tuple[TD3BC, SkillData, Path]) -> None:
    _, _, directory = trained
    policy = SkillPolicy.load(directory, SKILL)
    for bad in (np.zeros(9), np.zeros((2, 3, 10)), np.zeros((4, 7))):
        with pytest.raises(ValueError, match="observation shape"):
            policy(bad)
    with pytest.raises(ValueError, match="non-finite"):
        policy(np.full(10, np.nan))


def test_policy_bounds_observations_far_outside_the_data(
    trained: tuple[TD3BC, SkillData, Path],
) -> None:
    _, _, directory = trained
    policy = SkillPolicy.load(directory, SKILL)
    mean, std = policy.checkpoint.obs_mean, policy.checkpoint.obs_std
    np.testing.assert_allclose(policy(mean + 1e3 * std), policy(mean + OBS_CLIP * std), atol=1e-6)


def test_load_policies_loads_every_skill_of_a_directory(
    tmp_path: Path, trained: tuple[TD3BC, SkillData, Path]
) -> None:
    _, _, directory = trained
    checkpoint = load_checkpoint(directory, SKILL)
    checkpoint.skill = get_skill(OTHER_SKILL)
    save_checkpoint(directory, checkpoint)
    assert list(load_policies(directory)) == sorted([SKILL, OTHER_SKILL])
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(CheckpointError, match="no skill checkpoints"):
        load_policies(empty)
    with pytest.raises(CheckpointError, match="not found"):
        load_policies(tmp_path / "nowhere")
