"""The skills' data as TD3+BC trains on them: normalised transitions per skill and a replay
that samples one batch of every skill at once, each from its own seeded generator."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch

from osg_control.data.datasets import Dataset
from osg_control.errors import DatasetError
from osg_control.learning.checkpoints import OBS_CLIP, normalise_observations

ACTION_TOLERANCE = 1e-4
"""Relative amount by which a stored action may exceed its bound (float rounding) [-]."""
OBS_NORM_EPS = 1e-2
"""Added to each observation std before normalising [-] (``TD3BCConfig.obs_norm_eps``)."""
TCP_POSITION = slice(0, 3)
"""The observation's TCP position [m]: the features ``TD3BCConfig.obs_noise`` perturbs."""


def observation_stats(observations: np.ndarray, eps: float) -> tuple[np.ndarray, np.ndarray]:
    """Per-dimension mean and std (plus ``eps``) of a data set's observations.

    Args:
        observations: (N, obs_dim) array.
        eps: added to the std so constant dimensions do not divide by zero.

    Returns:
        ``(mean, std)``, each (obs_dim,) float32.
    """
    obs = observations.astype(np.float64)
    return obs.mean(0).astype(np.float32), (obs.std(0) + eps).astype(np.float32)


@dataclass
class SkillData:
    """One skill's transitions, normalised for training, and how to undo the normalisation.

    Attributes:
        name: the skill's name.
        transitions: (N, 2 * obs_dim + action_dim + 2) float32 rows
            ``[obs, action, reward, next_obs, done]``: obs normalised, action divided by
            ``action_scale`` (so in [-1, 1]), done = the episode terminated by success.
        obs_mean: (obs_dim,) observation mean.
        obs_std: (obs_dim,) observation std plus eps.
        action_scale: (action_dim,) physical size of a normalised action of 1.
    """

    name: str
    transitions: np.ndarray
    obs_mean: np.ndarray
    obs_std: np.ndarray
    action_scale: np.ndarray


def prepare_skill_data(
    dataset: Dataset,
    action_scale: np.ndarray,
    eps: float = OBS_NORM_EPS,
) -> SkillData:
    """Normalise a loaded data set into training transitions.

    Args:
        dataset: the skill's data set (``datasets.load_dataset``).
        action_scale: (action_dim,) per-dimension action bound, physical units (the
            domain's ``action_bounds``).
        eps: added to the observation std (default: ``OBS_NORM_EPS``, ``TD3BCConfig``'s default).

    Returns:
        The skill's training data.

    Raises:
        DatasetError: naming the file, if no episode succeeded (TD3+BC would learn nothing
            from sparse rewards) or a stored action exceeds ``action_scale``.
    """
    arrays = dataset.arrays
    if not dataset.episode_successes.any():
        raise DatasetError(
            f"{dataset.path}: no successful episode among {dataset.num_episodes}; "
            "cannot learn a skill from it"
        )
    scale = np.asarray(action_scale, dtype=np.float32)
    actions = arrays["actions"] / scale
    worst = np.abs(actions).max(0) if len(actions) else np.zeros_like(scale)
    if np.any(worst > 1.0 + ACTION_TOLERANCE):
        dim = int(np.argmax(worst))
        raise DatasetError(
            f"{dataset.path}: action dimension {dim} reaches {worst[dim] * scale[dim]:.6g}, "
            f"beyond its bound {scale[dim]:.6g}"
        )
    mean, std = observation_stats(arrays["observations"], eps)
    columns = [
        normalise_observations(arrays["observations"], mean, std),
        np.clip(actions, -1.0, 1.0),
        arrays["rewards"][:, None],
        normalise_observations(arrays["next_observations"], mean, std),
        arrays["terminations"][:, None],
    ]
    return SkillData(
        name=dataset.skill_name,
        transitions=np.concatenate(columns, axis=1, dtype=np.float32),
        obs_mean=mean,
        obs_std=std,
        action_scale=scale,
    )


@dataclass
class Batch:
    """One update's samples for K skills (B transitions each), on the training device.

    Attributes:
        observations: (K, B, obs_dim) normalised.
        actions: (K, B, action_dim) normalised.
        rewards: (K, B).
        next_observations: (K, B, obs_dim) normalised.
        dones: (K, B) 1.0 where the episode terminated by success.
        noise: (K, B, action_dim) standard normal draws for target policy smoothing.
    """

    observations: torch.Tensor
    actions: torch.Tensor
    rewards: torch.Tensor
    next_observations: torch.Tensor
    dones: torch.Tensor
    noise: torch.Tensor


class BatchedReplay:
    """The K skills' transitions in one tensor; each skill samples from its own part.

    Skill k draws its batch indices, then its smoothing noise, from its own generator
    seeded with ``seeds[k] + 1`` (``+ 1``: distinct from its weight initialisation), and
    with ``obs_noise`` its observation noise from a second one seeded with ``seeds[k] + 2``:
    its batches are those of a replay without the noise, but for the noise.
    """

    def __init__(
        self,
        data: Sequence[SkillData],
        batch_size: int,
        seeds: Sequence[int],
        device: str | torch.device = "cpu",
        obs_noise: float | Sequence[float] = 0.0,
    ) -> None:
        """Move the transitions to ``device`` and seed one generator per skill.

        Args:
            data: the K skills' training data.
            batch_size: transitions per skill per batch.
            seeds: the K skills' seeds.
            device: where batches are built.
            obs_noise: std [m] of the Gaussian noise added to the TCP position of every
                sampled observation and next observation (``TD3BCConfig.obs_noise``): one
                for all skills, or one per skill.

        Raises:
            ValueError: no skills, a seed or noise count that differs, or an ``obs_noise``
                negative or not finite.
        """
        if not data or len(data) != len(seeds):
            raise ValueError(f"need one seed per skill, got {len(data)} skills, {len(seeds)} seeds")
        noises = np.asarray(obs_noise, dtype=np.float64)
        noises = np.full(len(data), float(noises)) if noises.ndim == 0 else noises
        if noises.shape != (len(data),):
            raise ValueError(f"need one obs_noise per skill or one for all, got {obs_noise!r} "
                             f"for {len(data)} skills")  # fmt: skip
        if not np.all(np.isfinite(noises) & (noises >= 0)):
            raise ValueError(f"obs_noise must be finite and >= 0 [m], got {obs_noise!r}")
        self.device = torch.device(device)
        self.batch_size = batch_size
        self.obs_dim = data[0].obs_mean.shape[0]
        self.action_dim = data[0].action_scale.shape[0]
        self._sizes = [len(d.transitions) for d in data]
        offsets = np.concatenate([[0], np.cumsum(self._sizes)[:-1]])
        self._offsets = torch.as_tensor(offsets, device=self.device)[:, None]
        self._rows = torch.as_tensor(np.concatenate([d.transitions for d in data])).to(device)
        self._generators = [
            torch.Generator(device=self.device).manual_seed(seed + 1) for seed in seeds
        ]
        scale = np.zeros((len(data), 1, self.obs_dim), dtype=np.float32)
        for k, skill in enumerate(data):
            scale[k, 0, TCP_POSITION] = noises[k] / skill.obs_std[TCP_POSITION]
        self._obs_noise = torch.as_tensor(scale, device=self.device) if noises.any() else None
        """(K, 1, obs_dim): the noise's std in each skill's normalised units (None: none)."""
        self._noise_generators = [
            torch.Generator(device=self.device).manual_seed(seed + 2) for seed in seeds
        ]

    def keep(self, skills: Sequence[int]) -> None:
        """Go on sampling for the skills at positions ``skills`` only (in that order); each
        keeps its generator, so its batches continue as they would have."""
        self._sizes = [self._sizes[k] for k in skills]
        self._offsets = self._offsets[list(skills)]
        self._generators = [self._generators[k] for k in skills]
        self._noise_generators = [self._noise_generators[k] for k in skills]
        if self._obs_noise is not None:
            self._obs_noise = self._obs_noise[list(skills)]

    def sample(self) -> Batch:
        """Draw ``batch_size`` transitions (uniformly, with replacement) for every skill.

        Returns:
            The batch, every field with leading dimensions (K, B).
        """
        indices, noise = [], []
        for size, generator in zip(self._sizes, self._generators, strict=True):
            shape = (self.batch_size,)
            indices.append(torch.randint(size, shape, generator=generator, device=self.device))
            noise.append(
                torch.randn((*shape, self.action_dim), generator=generator, device=self.device)
            )
        rows = self._rows[torch.stack(indices) + self._offsets]
        obs, act = self.obs_dim, self.action_dim
        observations = rows[..., :obs]
        next_observations = rows[..., obs + act + 1 : 2 * obs + act + 1]
        if self._obs_noise is not None:
            observations, next_observations = self._perturbed(observations, next_observations)
        return Batch(
            observations=observations,
            actions=rows[..., obs : obs + act],
            rewards=rows[..., obs + act],
            next_observations=next_observations,
            dones=rows[..., -1],
            noise=torch.stack(noise),
        )

    def _perturbed(
        self, observations: torch.Tensor, next_observations: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """The observations with independent Gaussian noise on their TCP position (each
        skill's from its own generator), clipped like the data to ``±OBS_CLIP``."""
        assert self._obs_noise is not None
        shape = (2, self.batch_size, self.obs_dim)
        draws = torch.stack(
            [torch.randn(shape, generator=g, device=self.device) for g in self._noise_generators]
        )  # (K, 2, B, obs_dim)
        noisy = [
            (x + draws[:, i] * self._obs_noise).clamp(-OBS_CLIP, OBS_CLIP)
            for i, x in enumerate((observations, next_observations))
        ]
        return noisy[0], noisy[1]


# ----------------------------------------------------------------------------- networks
