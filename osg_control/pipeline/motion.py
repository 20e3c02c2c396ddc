"""The TCP filter's motion model, fitted on a domain's own data sets (the filter stage).

Each domain's arm answers its commands in its own way (the kitchen's arm moves 0.86 of a
sub-centimetre command and 0.22 of the last; FrankaKitchen's servos otherwise), so the
model is fitted per domain on the data its skills are trained on and shipped in the
defaults' manifest (``motion_model``), where the executor's filter reads it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from osg_control.control.estimator import fit_motion_model
from osg_control.data.datasets import load_dataset
from osg_control.domain.base import Domain


def fit_filter_motion(domain: Domain, data_dir: Path) -> tuple[float, float]:
    """``(k_now, k_prev)`` by least squares over every skill's data set in ``data_dir``.

    Raises:
        DatasetError: a data set missing or malformed (named).
    """
    observations, actions, following, starts = [], [], [], []
    offset = 0
    for skill in domain.skills:
        dataset = load_dataset(Path(data_dir) / f"{skill.name}.h5")
        arrays = dataset.arrays
        observations.append(arrays["observations"])
        actions.append(arrays["actions"])
        following.append(arrays["next_observations"])
        starts.append(dataset.episode_starts + offset)
        offset += dataset.num_steps
    return fit_motion_model(
        np.concatenate(observations),
        np.concatenate(actions),
        np.concatenate(following),
        np.concatenate(starts),
    )


def format_motion(motion: tuple[float, float]) -> str:
    """The fitted model as a line."""
    return f"TCP filter motion model: k_now {motion[0]:.3f}, k_prev {motion[1]:.3f}"
