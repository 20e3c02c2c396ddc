"""The state->skill classifier at run time: numpy forward pass and checkpoint files.

An MLP (22 -> 256 -> 256 -> classes, ReLU) on the normalised 10-D state and its 12-D motion
input (``classifier.motion``: the previous TCP command and a decaying memory of the
commands), trained by ``osg_control.classifier.train``. Prediction needs no torch. A
checkpoint is a folder with ``classifier.safetensors`` (the layer weights) and
``classifier.json`` (classes, normalisation, training configuration, seed, data-set digests,
package version); nothing is pickled."""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from safetensors import SafetensorError
from safetensors.numpy import load_file, save_file

from osg_control import __version__
from osg_control.classifier.data import (
    ClassifierData,
    LabelledStates,
    load_classifier_data,
)
from osg_control.classifier.metrics import EvaluationReport, evaluate_predictions
from osg_control.classifier.motion import MOTION_FEATURES
from osg_control.domain.base import Domain
from osg_control.domain.spaces import OBS_DIM
from osg_control.errors import CheckpointError
from osg_control.io_safety import atomic_write
from osg_control.json_files import read_json_object
from osg_control.learning.checkpoints import (
    check_finite,
    check_values_sha256,
    sha256_file,
    values_sha256,
)

WEIGHTS_FILE = "classifier.safetensors"
SIDECAR_FILE = "classifier.json"
CHECKPOINT_FORMAT = "osg-state-classifier"
CHECKPOINT_VERSION = 2
"""2: the inputs are the state and its motion input (version 1 read the state alone)."""
INPUT_DIM = OBS_DIM + MOTION_FEATURES
_STRUCTURAL_KEYS = ("format", "format_version", "classes", "normalisation", "weights_sha256")
_CHECKSUM_KEYS = ("normalisation_sha256",)
"""Sidecar keys checked on load and not kept in ``info``."""


def _as_input_batch(
    states: np.ndarray | Sequence[float], motion: np.ndarray | Sequence[float] | None
) -> np.ndarray:
    """Validate states (10,) or (B, 10) and their motion inputs (12,) or (B, 12); None:
    at rest (zeros). Returns the (B, 22) float32 inputs.

    Raises:
        ValueError: wrong shape or a NaN/inf entry, with the offending shape or rows.
    """
    array = np.asarray(states, dtype=np.float64)
    if array.ndim not in (1, 2) or array.shape[-1] != OBS_DIM:
        raise ValueError(f"state must have shape ({OBS_DIM},) or (B, {OBS_DIM}), got {array.shape}")
    batch = array.reshape(-1, OBS_DIM)
    if motion is None:
        moves = np.zeros((len(batch), MOTION_FEATURES))
    else:
        moves = np.asarray(motion, dtype=np.float64)
        if moves.shape[-1:] != (MOTION_FEATURES,) or moves.size != len(batch) * MOTION_FEATURES:
            raise ValueError(
                f"motion must have shape ({MOTION_FEATURES},) or (B, {MOTION_FEATURES}) for "
                f"{len(batch)} state(s), got {moves.shape}"
            )
        moves = moves.reshape(-1, MOTION_FEATURES)
    inputs = np.concatenate([batch, moves], axis=1)
    bad_rows = np.flatnonzero(~np.isfinite(inputs).all(axis=1))
    if len(bad_rows):
        raise ValueError(f"state contains NaN or inf (row(s) {bad_rows[:10].tolist()})")
    return inputs.astype(np.float32)


@dataclass
class StateClassifier:
    """A trained classifier: maps a 10-D state (and its motion input) to the movement skill
    it belongs to.

    Attributes:
        classes: class names; output ``i`` is ``classes[i]``.
        layers: (weight (out, in), bias (out,)) float32 per linear layer; ReLU between.
        mean: (22,) input mean subtracted before the first layer.
        std: (22,) positive input scale divided by after subtracting the mean.
        info: training record written to the sidecar: ``config``, ``seed``, ``datasets``
            (sha256 by skill), ``training`` and, once loaded, ``package_version``.
    """

    classes: tuple[str, ...]
    layers: tuple[tuple[np.ndarray, np.ndarray], ...]
    mean: np.ndarray
    std: np.ndarray
    info: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        """Check that the arrays chain from ``INPUT_DIM`` inputs to one output per class.

        Raises:
            ValueError: naming the mismatched array.
        """
        if self.mean.shape != (INPUT_DIM,) or self.std.shape != (INPUT_DIM,):
            raise ValueError(
                f"normalisation must be ({INPUT_DIM},) vectors, got {self.mean.shape} and "
                f"{self.std.shape}"
            )
        if not (np.all(np.isfinite(self.mean)) and np.all(np.isfinite(self.std))):
            raise ValueError("normalisation contains NaN or inf")
        if not np.all(self.std > 0):
            raise ValueError("normalisation std must be positive")
        width = INPUT_DIM
        for i, (weight, bias) in enumerate(self.layers):
            if weight.ndim != 2 or weight.shape[1] != width or bias.shape != (weight.shape[0],):
                raise ValueError(
                    f"layer {i}: weight {weight.shape} and bias {bias.shape} do not take "
                    f"{width} inputs"
                )
            width = weight.shape[0]
        if width != len(self.classes):
            raise ValueError(f"the last layer has {width} outputs for {len(self.classes)} classes")

    def logits(
        self, states: np.ndarray | Sequence[float], motion: np.ndarray | None = None
    ) -> np.ndarray:
        """Unnormalised class scores.

        Args:
            states: (10,) or (B, 10).
            motion: their motion inputs, (12,) or (B, 12) (``classifier.motion``); None:
                at rest.

        Returns:
            (B, n_classes) float32 (B = 1 for a single state).

        Raises:
            ValueError: wrong shape or NaN/inf in the states.
        """
        x = (_as_input_batch(states, motion) - self.mean) / self.std
        for weight, bias in self.layers[:-1]:
            x = np.maximum(x @ weight.T + bias, 0.0)
        weight, bias = self.layers[-1]
        return np.asarray(x @ weight.T + bias, dtype=np.float32)

    def predict_proba(
        self, states: np.ndarray | Sequence[float], motion: np.ndarray | None = None
    ) -> np.ndarray:
        """Class probabilities (softmax of the logits).

        Args:
            states: (10,) or (B, 10).
            motion: their motion inputs (``logits``); None: at rest.

        Returns:
            (n_classes,) for a single state, else (B, n_classes); rows sum to 1.

        Raises:
            ValueError: wrong shape or NaN/inf in the states.
        """
        logits = self.logits(states, motion)
        exp = np.exp(logits - logits.max(axis=1, keepdims=True))
        proba = exp / exp.sum(axis=1, keepdims=True)
        return proba[0] if np.ndim(states) == 1 else proba

    def predict_index(
        self, states: np.ndarray | Sequence[float], motion: np.ndarray | None = None
    ) -> np.ndarray:
        """Most likely class index of each state.

        Args:
            states: (10,) or (B, 10).
            motion: their motion inputs (``logits``); None: at rest.

        Returns:
            (B,) int64 (B = 1 for a single state).

        Raises:
            ValueError: wrong shape or NaN/inf in the states.
        """
        return np.argmax(self.logits(states, motion), axis=1).astype(np.int64)

    def predict(
        self, states: np.ndarray | Sequence[float], motion: np.ndarray | None = None
    ) -> str | list[str]:
        """Most likely skill name.

        Args:
            states: (10,) or (B, 10).
            motion: their motion inputs (``logits``); None: at rest.

        Returns:
            The skill name for a single state, else a list of B names.

        Raises:
            ValueError: wrong shape or NaN/inf in the states.
        """
        names = [self.classes[i] for i in self.predict_index(states, motion)]
        return names[0] if np.ndim(states) == 1 else names

    def save(self, directory: Path) -> Path:
        """Write ``classifier.safetensors`` and ``classifier.json`` into ``directory``.

        Each file is written to a temporary name and renamed, weights first.

        Args:
            directory: created if missing.

        Returns:
            The sidecar's path.
        """
        directory = Path(directory)
        tensors: dict[str, np.ndarray] = {}
        for i, (weight, bias) in enumerate(self.layers):
            tensors[f"layers.{i}.weight"] = np.ascontiguousarray(weight, dtype=np.float32)
            tensors[f"layers.{i}.bias"] = np.ascontiguousarray(bias, dtype=np.float32)
        weights_path = directory / WEIGHTS_FILE
        atomic_write(weights_path, lambda tmp: save_file(tensors, str(tmp)))
        sidecar = {
            **self.info,
            "format": CHECKPOINT_FORMAT,
            "format_version": CHECKPOINT_VERSION,
            "classes": list(self.classes),
            "normalisation": {"mean": self.mean.tolist(), "std": self.std.tolist()},
            "weights_sha256": sha256_file(weights_path),
            "package_version": __version__,
        }
        sidecar["normalisation_sha256"] = values_sha256(sidecar["normalisation"])
        sidecar_path = directory / SIDECAR_FILE
        text = json.dumps(sidecar, indent=2, sort_keys=True) + "\n"
        atomic_write(sidecar_path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
        return sidecar_path

    @classmethod
    def load(
        cls, directory: Path, expected_classes: Sequence[str] | None = None
    ) -> StateClassifier:
        """Read a checkpoint folder written by ``save``.

        Args:
            directory: the folder.
            expected_classes: the class list the caller needs (a domain's
                ``movement_classes``); None accepts the checkpoint's.

        Returns:
            The classifier.

        Raises:
            CheckpointError: a missing or corrupt file (named), weights that do not match the
                sidecar, or a class list other than ``expected_classes`` (both lists named).
        """
        directory = Path(directory)
        sidecar_path = directory / SIDECAR_FILE
        weights_path = directory / WEIGHTS_FILE
        for path in (sidecar_path, weights_path):
            if not path.exists():
                raise CheckpointError(f"{path}: classifier checkpoint file not found")
            if not path.is_file():
                raise CheckpointError(f"{path}: classifier checkpoint is not a regular file")
        sidecar = read_json_object(sidecar_path, "classifier sidecar", CheckpointError)
        if sidecar.get("format") != CHECKPOINT_FORMAT:
            raise CheckpointError(f"{sidecar_path}: not a {CHECKPOINT_FORMAT} sidecar")
        missing = [key for key in _STRUCTURAL_KEYS if key not in sidecar]
        if missing:
            raise CheckpointError(f"{sidecar_path}: missing field(s) {missing}")
        if sidecar["format_version"] != CHECKPOINT_VERSION:
            raise CheckpointError(
                f"{sidecar_path}: format version {sidecar['format_version']}, this package "
                f"reads {CHECKPOINT_VERSION}"
            )
        expected = sidecar["classes"] if expected_classes is None else list(expected_classes)
        if sidecar["classes"] != expected:
            raise CheckpointError(
                f"{sidecar_path}: checkpoint classes {sidecar['classes']} do not match the "
                f"current movement skills {expected}; retrain with `osg classifier train`"
            )
        if "normalisation_sha256" in sidecar:  # written since it exists
            check_values_sha256(
                sidecar_path,
                sidecar["normalisation"],
                sidecar["normalisation_sha256"],
                "normalisation mean and std",
            )
        if sha256_file(weights_path) != sidecar["weights_sha256"]:
            raise CheckpointError(
                f"{weights_path}: contents do not match the sha256 recorded in {sidecar_path}"
            )
        try:
            tensors = load_file(str(weights_path))
            layers = tuple(
                (tensors[f"layers.{i}.weight"], tensors[f"layers.{i}.bias"])
                for i in range(sum(1 for key in tensors if key.endswith(".weight")))
            )
        except (SafetensorError, OSError, KeyError) as err:
            raise CheckpointError(f"{weights_path}: corrupt classifier weights ({err})") from err
        check_finite(weights_path, tensors)
        try:
            return cls(
                classes=tuple(sidecar["classes"]),
                layers=layers,
                mean=np.asarray(sidecar["normalisation"]["mean"], dtype=np.float32),
                std=np.asarray(sidecar["normalisation"]["std"], dtype=np.float32),
                info={
                    k: v
                    for k, v in sidecar.items()
                    if k not in _STRUCTURAL_KEYS and k not in _CHECKSUM_KEYS
                },
            )
        except (KeyError, TypeError, ValueError) as err:
            raise CheckpointError(
                f"{directory}: weights and sidecar do not form a classifier ({err})"
            ) from err


def evaluate(
    model: StateClassifier, states: LabelledStates, starts: np.ndarray
) -> EvaluationReport:
    """Table II of ``model`` on labelled states, with the nearest-node baseline.

    Args:
        model: the classifier; its classes must be in ``class_order``.
        states: the test states.
        starts: (K, 3) start-node positions of its classes (``data.class_starts``).

    Returns:
        The report.
    """
    return evaluate_predictions(
        states.observations,
        states.labels,
        model.predict_index(states.observations, states.motion),
        model.classes,
        starts,
    )


def reload_split(
    model: StateClassifier, data_dir: Path, domain: Domain | None = None
) -> tuple[ClassifierData, bool]:
    """Re-create the train/test split a classifier was trained with.

    Args:
        model: a trained classifier (its ``info["split"]`` names the seed and fraction).
        data_dir: folder holding ``<skill>.h5`` for every class.

    Returns:
        The split data, and whether the files are the ones the model was trained on (by
        sha256); if not, the test states may overlap its training states.

    Raises:
        CheckpointError: the checkpoint records no split.
        DatasetError: a data set is missing or malformed.
    """
    try:
        seed, test_fraction = (
            int(model.info["split"]["seed"]),
            float(model.info["split"]["test_fraction"]),
        )
    except (KeyError, TypeError, ValueError) as err:
        raise CheckpointError(f"classifier checkpoint records no valid split ({err})") from err
    data = load_classifier_data(data_dir, model.classes, seed, test_fraction, domain)
    return data, data.sha256 == model.info.get("datasets")
