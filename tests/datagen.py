"""Small synthetic data sets for the tests of loaders and validation."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from osg_control.data.datasets import Episode, write_episodes
from osg_control.domain.spaces import ACTION_DIM, OBS_DIM
from osg_control.kitchen.skills import get_skill
from osg_control.kitchen.world import world_fields

WORLD_FIELDS = world_fields()
"""The one-cube kitchen's world vector fields, the valve's place included."""


def synthetic_episode(steps: int = 6, success: bool = True, seed: int = 0) -> Episode:
    """An episode of ``steps`` random finite steps; the last is rewarded if ``success``."""
    rng = np.random.default_rng(seed)
    rewards = np.zeros(steps, dtype=np.float32)
    rewards[-1] = 1.0 if success else 0.0
    truncations = np.zeros(steps, dtype=bool)
    truncations[-1] = not success
    return Episode(
        observations=rng.normal(size=(steps, OBS_DIM)).astype(np.float32),
        next_observations=rng.normal(size=(steps, OBS_DIM)).astype(np.float32),
        actions=rng.uniform(-0.01, 0.01, size=(steps, ACTION_DIM)).astype(np.float32),
        rewards=rewards,
        terminations=rewards > 0,
        truncations=truncations,
        world_states=np.zeros((steps, len(WORLD_FIELDS)), dtype=np.float32),
    )


def write_synthetic_dataset(path, episodes: int = 3, skill: str = "grab-cube", seed: int = 0):
    """Write ``episodes`` synthetic episodes (alternating success) as a data set of ``skill``."""
    eps = [synthetic_episode(4 + i, success=i % 2 == 0, seed=i) for i in range(episodes)]
    write_episodes(
        path,
        eps,
        {"skill": get_skill(skill).to_json(), "seed": seed, "world_fields": ",".join(WORLD_FIELDS)},
    )
    return path


def chained_dataset(path: Path) -> Path:
    """A tiny data set whose next observations chain (what Minari's T+1 layout needs)."""
    episodes = []
    for index in range(2):
        episode = synthetic_episode(5, success=index == 0, seed=index)
        episode.next_observations[:-1] = episode.observations[1:]
        episodes.append(episode)
    attrs = {
        "skill": get_skill("grab-cube").to_json(),
        "seed": 0,
        "world_fields": ",".join(WORLD_FIELDS),
    }
    write_episodes(path, episodes, attrs)
    return path
