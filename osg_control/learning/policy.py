"""Run-time skill policies: a checkpoint's actor evaluated with plain numpy matmuls."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from osg_control.domain.spaces import ACTION_DIM, OBS_DIM
from osg_control.errors import CheckpointError
from osg_control.learning.checkpoints import (
    SIDECAR_SUFFIX,
    Checkpoint,
    load_checkpoint,
    normalise_observations,
)


class SkillPolicy:
    """A learned skill's deterministic policy: observation in, physical action out."""

    def __init__(self, checkpoint: Checkpoint) -> None:
        """Wrap a loaded checkpoint.

        Args:
            checkpoint: from ``checkpoints.load_checkpoint``.
        """
        self.checkpoint = checkpoint
        self.skill = checkpoint.skill

    @classmethod
    def load(
        cls, directory: str | Path, name: str, obs_dim: int = OBS_DIM, action_dim: int = ACTION_DIM
    ) -> SkillPolicy:
        """Load skill ``name``'s policy from a checkpoint directory.

        Args:
            directory: holding ``<name>.safetensors`` and ``<name>.json``.
            name: the skill.
            obs_dim: observation size the caller will feed.
            action_dim: action size the caller expects.

        Returns:
            The policy.

        Raises:
            CheckpointError: see ``checkpoints.load_checkpoint``.
        """
        return cls(load_checkpoint(directory, name, obs_dim, action_dim))

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        """The action for one observation or a batch.

        Args:
            obs: (obs_dim,) or (B, obs_dim) observations, raw (not normalised).

        Returns:
            (action_dim,) or (B, action_dim) float32 actions in physical units
            (position m, angles rad, gripper command), each within ``action_scale``.

        Raises:
            ValueError: a wrong shape or a non-finite value.
        """
        ckpt = self.checkpoint
        x = np.asarray(obs, dtype=np.float32)
        if x.ndim not in (1, 2) or x.shape[-1] != ckpt.obs_dim:
            raise ValueError(
                f"skill {self.skill.name!r}: observation shape {x.shape}, expected "
                f"({ckpt.obs_dim},) or (B, {ckpt.obs_dim})"
            )
        if not np.all(np.isfinite(x)):
            raise ValueError(f"skill {self.skill.name!r}: non-finite observation {x}")
        x = normalise_observations(x, ckpt.obs_mean, ckpt.obs_std)
        *hidden, (weight, bias) = ckpt.layers
        for w, b in hidden:
            x = np.maximum(x @ w + b, 0.0)
        return np.tanh(x @ weight + bias) * ckpt.action_scale


def load_policies(directory: str | Path) -> dict[str, SkillPolicy]:
    """Load every skill checkpoint in a directory.

    Args:
        directory: holding ``<name>.json`` / ``<name>.safetensors`` pairs.

    Returns:
        Policies by skill name, in name order.

    Raises:
        CheckpointError: the directory is missing or holds no checkpoint, or one of them
            fails to load (see ``checkpoints.load_checkpoint``).
    """
    directory = Path(directory).expanduser()
    if not directory.is_dir():
        raise CheckpointError(f"{directory}: checkpoint directory not found")
    names = sorted(path.stem for path in directory.glob(f"*{SIDECAR_SUFFIX}"))
    if not names:
        raise CheckpointError(f"{directory}: no skill checkpoints (*{SIDECAR_SUFFIX})")
    return {name: SkillPolicy.load(directory, name) for name in names}
