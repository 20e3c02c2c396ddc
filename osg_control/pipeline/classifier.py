"""The classifier stage: the state -> movement skill classifier from the movement data sets
(split 80/20 by episode; the epoch chosen on a validation split of the training episodes),
saved into a bundle's ``classifier/``."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from osg_control.classifier.data import load_classifier_data, movement_classes
from osg_control.classifier.train import TrainConfig, train_classifier
from osg_control.domain.base import Domain
from osg_control.io_safety import check_output_dir


@dataclass(frozen=True)
class TrainedClassifier:
    """What the stage wrote.

    Attributes:
        directory: the checkpoint folder.
        sidecar: its JSON sidecar.
        train_states, test_states: how many states each split holds.
        info: the sidecar's training record (config, split, data set digests, losses).
    """

    directory: Path
    sidecar: Path
    train_states: int
    test_states: int
    info: dict[str, Any]


def train_state_classifier(
    domain: Domain,
    data_dir: Path,
    out: Path,
    seed: int = 0,
    config: TrainConfig | None = None,
    progress: bool = True,
) -> TrainedClassifier:
    """Train the classifier on the movement skills' data sets and save it in ``out``.

    Args:
        data_dir: ``<skill>.h5`` for every movement skill.
        out: the checkpoint folder (checked before training).
        seed: the split, initialisation and shuffle seed (overrides ``config``'s).
        config: training settings (default: ``TrainConfig()``).
        progress: a progress bar over epochs on stderr.

    Raises:
        OutputError: ``out`` cannot be written.
        DatasetError: a movement data set missing or malformed.
    """
    settings = replace(config or TrainConfig(), seed=seed)
    folder = check_output_dir(out, "classifier folder")
    data = load_classifier_data(
        data_dir,
        movement_classes(domain),
        seed,
        domain=domain,
        validation_fraction=settings.validation_fraction,
    )
    model = train_classifier(data, settings, progress=progress)
    sidecar = model.save(folder)
    return TrainedClassifier(folder, sidecar, len(data.train), len(data.test), dict(model.info))


def format_classifier(trained: TrainedClassifier) -> str:
    """The split sizes, the final training loss and the folder."""
    losses = trained.info.get("training", {}).get("epoch_losses", [float("nan")])
    return (
        f"trained on {trained.train_states} states, tested on {trained.test_states} held-out "
        f"states (split by episode); final training loss {losses[-1]:.4f}\n"
        f"saved {trained.directory}"
    )
