"""Training the state->skill classifier with torch: seeded and deterministic on CPU.

Paper defaults: a fully connected net with two hidden layers of 256, 9 epochs, batches of
1028, Adam (learning rate 1e-3), cross-entropy. Inputs are normalised with the training
states' mean and standard deviation, which the returned ``StateClassifier`` keeps.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import torch
from torch import nn
from tqdm import tqdm

from osg_control.classifier.data import ClassifierData
from osg_control.classifier.model import INPUT_DIM, StateClassifier
from osg_control.errors import TrainingError

MIN_STD = 1e-6
"""An input whose training std is below this (e.g. a constant gripper command) is not scaled."""


@dataclass(frozen=True)
class TrainConfig:
    """How to train.

    Attributes:
        epochs: passes over the training states.
        batch_size: states per gradient step.
        learning_rate: Adam's step size.
        hidden: widths of the hidden layers.
        seed: seeds the weight initialisation and the batch shuffling.
        threads: torch CPU threads while training; more do not speed up so small a net,
            and on a busy machine they slow it down by an order of magnitude.
    """

    epochs: int = 9
    batch_size: int = 1028
    learning_rate: float = 1e-3
    hidden: tuple[int, ...] = (256, 256)
    seed: int = 0
    threads: int = 1

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


def _fit(
    inputs: torch.Tensor,
    targets: torch.Tensor,
    n_classes: int,
    config: TrainConfig,
    progress: bool,
) -> tuple[nn.Sequential, list[float]]:
    """Initialise and train the net on normalised inputs; return it and each epoch's loss."""
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
        bar.set_postfix(loss=f"{epoch_losses[-1]:.4f}")
    return net, epoch_losses


def train_classifier(
    data: ClassifierData, config: TrainConfig, progress: bool = False
) -> StateClassifier:
    """Train on ``data.train``.

    Args:
        data: labelled, split states.
        config: training settings.
        progress: show a tqdm bar over epochs (on stderr).

    Returns:
        The classifier; its ``info`` records the config, split, data-set digests and the
        mean training loss of each epoch.

    Raises:
        ValueError: no training states.
    """
    if len(data.train) == 0:
        raise ValueError("no training states")
    train_inputs = data.train.inputs
    mean, std = normalisation(train_inputs)
    inputs = torch.from_numpy((train_inputs - mean) / std)
    targets = torch.from_numpy(data.train.labels)
    previous_threads = torch.get_num_threads()
    torch.set_num_threads(config.threads)
    try:
        net, epoch_losses = _fit(inputs, targets, len(data.classes), config, progress)
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
            "split": {"seed": data.seed, "test_fraction": data.test_fraction, "by": "episode"},
            "datasets": dict(data.sha256),
            "training": {
                "epoch_losses": epoch_losses,
                "train_states": len(data.train),
                "test_states": len(data.test),
            },
        },
    )
