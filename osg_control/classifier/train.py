"""Training the state->skill classifier with torch: seeded and deterministic on CPU.

The paper's net and optimiser: a fully connected net with two hidden layers of 256, batches
of 1028, Adam (learning rate 1e-3), cross-entropy. The paper trains 9 epochs; by default
this trains up to ``TrainConfig.epochs`` and keeps the epoch whose weights score the best
corrected accuracy on a validation split of the training episodes (``PAPER_CONFIG`` is the
paper's fixed 9 epochs without one). Inputs are normalised with the training states' mean
and standard deviation, which the returned ``StateClassifier`` keeps.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import torch
from torch import nn
from tqdm import tqdm

from osg_control.classifier.data import ClassifierData, LabelledStates
from osg_control.classifier.metrics import confusion_matrix, corrected_accuracy
from osg_control.classifier.model import INPUT_DIM, StateClassifier
from osg_control.errors import TrainingError

MIN_STD = 1e-6
"""An input whose training std is below this (e.g. a constant gripper command) is not scaled."""


@dataclass(frozen=True)
class TrainConfig:
    """How to train.

    Attributes:
        epochs: passes over the training states; with a validation split, the most passes,
            of which the one scoring best on the validation states is kept.
        batch_size: states per gradient step.
        learning_rate: Adam's step size.
        hidden: widths of the hidden layers.
        seed: seeds the weight initialisation and the batch shuffling.
        threads: torch CPU threads while training; more do not speed up so small a net,
            and on a busy machine they slow it down by an order of magnitude.
        validation_fraction: fraction of each data set's training episodes set aside to
            choose the epoch (``load_classifier_data(validation_fraction=...)``); 0 trains
            exactly ``epochs`` epochs on all of them (the paper's protocol).
    """

    epochs: int = 40
    batch_size: int = 1028
    learning_rate: float = 1e-3
    hidden: tuple[int, ...] = (256, 256)
    seed: int = 0
    threads: int = 1
    validation_fraction: float = 0.2

    def __post_init__(self) -> None:
        """Reject non-positive settings.

        Raises:
            ValueError: naming the setting.
        """
        for name in ("epochs", "batch_size", "learning_rate", "threads"):
            if getattr(self, name) <= 0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)}")
        if not self.hidden or min(self.hidden) <= 0:
            raise ValueError(f"hidden must be positive layer widths, got {self.hidden}")
        if not 0.0 <= self.validation_fraction < 1.0:
            raise ValueError(
                f"validation_fraction must be in [0, 1), got {self.validation_fraction}"
            )


PAPER_CONFIG = TrainConfig(epochs=9, validation_fraction=0.0)
"""The paper's training: 9 epochs on all training episodes, no epoch choice."""


def normalisation(observations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-input mean and scale of the training states.

    Args:
        observations: (N, ``INPUT_DIM``) training inputs, N >= 1.

    Returns:
        (mean, std) as (``INPUT_DIM``,) float32; a std below ``MIN_STD`` is replaced by 1.
    """
    mean = observations.mean(axis=0, dtype=np.float64)
    std = observations.std(axis=0, dtype=np.float64)
    std[std < MIN_STD] = 1.0
    return mean.astype(np.float32), std.astype(np.float32)


def _build_net(widths: list[int]) -> nn.Sequential:
    modules: list[nn.Module] = []
    for n_in, n_out in zip(widths[:-1], widths[1:], strict=True):
        modules += [nn.Linear(n_in, n_out), nn.ReLU()]
    return nn.Sequential(*modules[:-1])


class _EpochChoice:
    """The validation record of one training run: each epoch's corrected accuracy on the
    validation states and the weights of the best so far (ties keep the later epoch)."""

    def __init__(
        self, validation: LabelledStates, mean: np.ndarray, std: np.ndarray, n_classes: int
    ) -> None:
        self.inputs = torch.from_numpy((validation.inputs - mean) / std)  # as the training's
        self.labels = validation.labels
        self.n_classes = n_classes
        self.scores: list[float] = []
        self.best_state: dict[str, torch.Tensor] | None = None
        self.best_epoch = 0

    def score(self, net: nn.Sequential) -> None:
        """Score the net after an epoch; keep its weights if at least as good as the best."""
        with torch.no_grad():
            predictions = net(self.inputs).argmax(dim=1).numpy()
        score = corrected_accuracy(confusion_matrix(self.labels, predictions, self.n_classes))
        self.scores.append(score)
        if score >= max(self.scores):
            self.best_epoch = len(self.scores)
            self.best_state = {k: v.detach().clone() for k, v in net.state_dict().items()}


def _fit(
    inputs: torch.Tensor,
    targets: torch.Tensor,
    n_classes: int,
    config: TrainConfig,
    progress: bool,
    choice: _EpochChoice | None = None,
) -> tuple[nn.Sequential, list[float]]:
    """Initialise and train the net on normalised inputs; return it and each epoch's loss.
    With ``choice``, every epoch is scored on its validation states and the net returned
    carries the best epoch's weights."""
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(config.seed)
        net = _build_net([INPUT_DIM, *config.hidden, n_classes])
    generator = torch.Generator().manual_seed(config.seed)
    optimizer = torch.optim.Adam(net.parameters(), lr=config.learning_rate)
    loss_fn = nn.CrossEntropyLoss()
    epoch_losses: list[float] = []
    bar = tqdm(range(config.epochs), desc="classifier", unit="epoch", disable=not progress)
    for _ in bar:
        total = 0.0
        for batch in torch.randperm(len(targets), generator=generator).split(config.batch_size):
            loss = loss_fn(net(inputs[batch]), targets[batch])
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            total += loss.item() * len(batch)
        epoch_losses.append(total / len(targets))
        if not math.isfinite(epoch_losses[-1]):
            raise TrainingError(
                f"classifier loss became {epoch_losses[-1]} in epoch {len(epoch_losses)}; "
                "nothing saved (check the data sets for extreme values)"
            )
        if choice is None:
            bar.set_postfix(loss=f"{epoch_losses[-1]:.4f}")
            continue
        choice.score(net)
        bar.set_postfix(loss=f"{epoch_losses[-1]:.4f}", validation=f"{choice.scores[-1]:.4f}")
    if choice is not None and choice.best_state is not None:
        net.load_state_dict(choice.best_state)
    return net, epoch_losses


def train_classifier(
    data: ClassifierData, config: TrainConfig, progress: bool = False
) -> StateClassifier:
    """Train on ``data.train``; with a validation split, keep its best epoch.

    Args:
        data: labelled, split states, loaded with ``config.validation_fraction``.
        config: training settings.
        progress: show a tqdm bar over epochs (on stderr).

    Returns:
        The classifier; its ``info`` records the config, split, data-set digests, the
        mean training loss of each epoch and, with a validation split, each epoch's
        validation corrected accuracy and the epoch kept.

    Raises:
        ValueError: no training states, no validation states where the config asks for
            them, or data split with another validation fraction than the config's.
    """
    if len(data.train) == 0:
        raise ValueError("no training states")
    if data.validation_fraction != config.validation_fraction:
        raise ValueError(
            f"the data hold a validation split of {data.validation_fraction} and the config "
            f"asks for {config.validation_fraction}; load them with "
            f"load_classifier_data(..., validation_fraction={config.validation_fraction})"
        )
    if config.validation_fraction > 0.0 and len(data.validation) == 0:
        raise ValueError("no validation states")
    train_inputs = data.train.inputs
    mean, std = normalisation(train_inputs)
    inputs = torch.from_numpy((train_inputs - mean) / std)
    targets = torch.from_numpy(data.train.labels)
    choice = (
        _EpochChoice(data.validation, mean, std, len(data.classes))
        if len(data.validation)
        else None
    )
    previous_threads = torch.get_num_threads()
    torch.set_num_threads(config.threads)
    try:
        net, epoch_losses = _fit(inputs, targets, len(data.classes), config, progress, choice)
    finally:
        torch.set_num_threads(previous_threads)
    layers = tuple(
        (m.weight.detach().numpy().copy(), m.bias.detach().numpy().copy())
        for m in net
        if isinstance(m, nn.Linear)
    )
    return StateClassifier(
        classes=data.classes,
        layers=layers,
        mean=mean,
        std=std,
        info={
            "config": {**asdict(config), "hidden": list(config.hidden)},
            "seed": config.seed,
            "split": {
                "seed": data.seed,
                "test_fraction": data.test_fraction,
                "validation_fraction": data.validation_fraction,
                "by": "episode",
            },
            "datasets": dict(data.sha256),
            "training": {
                "epoch_losses": epoch_losses,
                "train_states": len(data.train),
                "test_states": len(data.test),
                "validation_states": len(data.validation),
                **(
                    {}
                    if choice is None
                    else {
                        "validation_corrected_accuracy": choice.scores,
                        "epoch_kept": choice.best_epoch,
                    }
                ),
            },
        },
    )
