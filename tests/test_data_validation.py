"""Non-finite or inconsistent data never trains: every field of a data set is validated
(naming file and field), non-finite weights are refused at save and load (naming file and
tensor), and training stops on a non-finite loss without writing a checkpoint."""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path

import h5py
import numpy as np
import pytest
import torch
from safetensors.numpy import load_file, save_file
from test_td3bc import SMALL, toy_checkpoint, toy_data, train

from osg_control.cli import main
from osg_control.data.datasets import load_dataset
from osg_control.domain.registry import get_domain
from osg_control.errors import EXIT_CODES, CheckpointError, DatasetError, TrainingError
from osg_control.learning.checkpoints import checkpoint_paths, load_checkpoint, save_checkpoint
from osg_control.learning.replay import BatchedReplay
from osg_control.learning.td3bc import TD3BC
from osg_control.pipeline.training_loop import train_with_progress
from tests.datagen import write_synthetic_dataset

KITCHEN = get_domain("kitchen")


def _set(key, transform):
    def corrupt(f: h5py.File) -> None:
        value = transform(f[key][()])
        del f[key]
        f.create_dataset(key, data=value)

    return corrupt


def _nan_at(index):
    def transform(value):
        value = value.astype(np.float32)
        value[index] = np.nan
        return value

    return transform


CORRUPTIONS = [
    ("rewards", _set("rewards", _nan_at(0))),
    ("next_observations", _set("next_observations", _nan_at((2, 3)))),
    ("world_states", _set("world_states", lambda v: np.full_like(v, np.inf))),
    ("observations", _set("observations", _nan_at((1, 0)))),
    ("rewards", _set("rewards", lambda v: v * 0.5)),
    ("rewards", _set("rewards", lambda v: v.astype(np.int64))),
    ("terminations", _set("terminations", lambda v: ~v)),
    ("episode_successes", _set("episode_successes", lambda v: ~v)),
    ("episode_lengths", _set("episode_lengths", lambda v: v[::-1].copy())),
    ("episode_lengths", _set("episode_lengths", lambda v: np.concatenate([[0], v[1:]]))),
    ("episode_starts", _set("episode_starts", lambda v: v + 1)),
    ("episode_ids", _set("episode_ids", np.zeros_like)),
    ("actions", _set("actions", lambda v: v[:, :6])),
    ("episode_successes", _set("episode_successes", lambda v: v.astype(np.float32))),
    ("seed", lambda f: f.attrs.__setitem__("seed", -1)),
    ("skill", lambda f: f.attrs.__setitem__("skill", "not json")),
]


@pytest.mark.parametrize(("field", "corrupt"), CORRUPTIONS)
def test_every_field_is_validated_and_named(field, corrupt, tmp_path):
    path = write_synthetic_dataset(tmp_path / "grab-cube.h5")
    load_dataset(path)  # valid before the corruption
    with h5py.File(path, "a") as f:
        corrupt(f)
    with pytest.raises(DatasetError) as err:
        load_dataset(path)
    assert str(path) in str(err.value) and field in str(err.value)


def test_train_refuses_a_nan_reward_before_training(tmp_path, monkeypatch, capsys):
    path = write_synthetic_dataset(tmp_path / "data" / "grab-cube.h5")
    with h5py.File(path, "a") as f:
        _set("rewards", _nan_at(1))(f)
    out = tmp_path / "skills"
    argv = ["train", "--skill", "grab-cube", "--steps", "10", "--data", str(tmp_path / "data")]
    assert main([*argv, "--out", str(out)]) == EXIT_CODES["failure"]
    assert "'rewards'" in capsys.readouterr().err
    assert not list(out.glob("*.safetensors"))


def _poison_saved_weights(directory: Path, name: str) -> Path:
    """Put a NaN into a saved checkpoint's weights, with a matching sha256 in the sidecar."""
    weights_path, sidecar_path = checkpoint_paths(directory, name)
    tensors = load_file(str(weights_path))
    tensors["layers.1.weight"][0, 0] = np.nan
    save_file(tensors, str(weights_path), metadata={"skill": name})
    sidecar = json.loads(sidecar_path.read_text())
    sidecar["weights_sha256"] = hashlib.sha256(weights_path.read_bytes()).hexdigest()
    sidecar_path.write_text(json.dumps(sidecar))
    return weights_path


def test_non_finite_weights_are_refused_at_save_and_load(tmp_path):
    data = toy_data(tmp_path)
    trainer = train([data], [0], steps=2)
    checkpoint = toy_checkpoint(trainer, data, steps=2, seed=0)
    save_checkpoint(tmp_path / "skills", checkpoint)
    weights_path = _poison_saved_weights(tmp_path / "skills", checkpoint.skill.name)
    with pytest.raises(CheckpointError, match=r"layers\.1\.weight") as err:
        load_checkpoint(tmp_path / "skills", checkpoint.skill.name)
    assert str(weights_path) in str(err.value)
    layers = [(w.copy(), b.copy()) for w, b in checkpoint.layers]
    layers[0][1][0] = np.inf
    bad = dataclasses.replace(checkpoint, layers=layers)
    with pytest.raises(CheckpointError, match=r"layers\.0\.bias"):
        save_checkpoint(tmp_path / "other", bad)
    assert not (tmp_path / "other").exists() or not list((tmp_path / "other").iterdir())


def test_classifier_with_non_finite_weights_is_refused(tmp_path):
    from test_classifier import FAST, write_movement_datasets

    from osg_control.classifier.data import load_classifier_data, movement_classes
    from osg_control.classifier.model import SIDECAR_FILE, WEIGHTS_FILE, StateClassifier
    from osg_control.classifier.train import train_classifier

    write_movement_datasets(tmp_path / "data")
    data = load_classifier_data(tmp_path / "data", movement_classes(KITCHEN), 0)
    model = train_classifier(dataclasses.replace(data), dataclasses.replace(FAST, epochs=1))
    model.save(tmp_path / "clf")
    tensors = load_file(str(tmp_path / "clf" / WEIGHTS_FILE))
    tensors["layers.0.weight"][:] = np.nan
    save_file(tensors, str(tmp_path / "clf" / WEIGHTS_FILE))
    sidecar = json.loads((tmp_path / "clf" / SIDECAR_FILE).read_text())
    sidecar["weights_sha256"] = hashlib.sha256(
        (tmp_path / "clf" / WEIGHTS_FILE).read_bytes()
    ).hexdigest()
    (tmp_path / "clf" / SIDECAR_FILE).write_text(json.dumps(sidecar))
    with pytest.raises(CheckpointError, match=r"classifier\.safetensors.*layers\.0\.weight"):
        StateClassifier.load(tmp_path / "clf")


@pytest.mark.slow
def test_training_stops_on_a_non_finite_loss(tmp_path):
    data = toy_data(tmp_path)
    config = dataclasses.replace(SMALL, critic_lr=1e38, actor_lr=1e38)
    trainer = TD3BC(config, [0])
    replay = BatchedReplay([data], config.batch_size, [0])
    with pytest.raises(TrainingError, match="non-finite at update 100 for skill"):
        train_with_progress(trainer, replay, 200, ["grab-cube"])
    assert trainer.steps == 100


def test_finite_losses_pass():
    from osg_control.pipeline.training_loop import check_finite_losses

    check_finite_losses({"critic_loss": torch.tensor([0.1, 2.0])}, 1, ["a", "b"])
    with pytest.raises(TrainingError, match=r"\['b'\]"):
        check_finite_losses({"critic_loss": torch.tensor([0.1, float("nan")])}, 1, ["a", "b"])
