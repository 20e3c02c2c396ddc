"""Gymnasium ids of the package's environments, registered on ``import osg_control``.

Each id maps to a string entry point, so registering imports nothing heavier than
Gymnasium itself; MuJoCo and the kitchen load on the first ``gymnasium.make``.
"""

from __future__ import annotations

ENVS: dict[str, tuple[str, int]] = {
    "osg/Kitchen-v0": ("osg_control.kitchen.env:KitchenEnv", 200),
}
"""Gymnasium id -> (entry point, ``max_episode_steps``: ``EnvConfig.max_steps``, above
every skill's own budget, which the env enforces itself when made with ``skill=``)."""


def register_envs() -> None:
    """Register every id in ``ENVS`` with Gymnasium (an id already registered is kept)."""
    from gymnasium.envs.registration import register, registry

    for env_id, (entry_point, max_steps) in ENVS.items():
        if env_id not in registry:
            register(env_id, entry_point=entry_point, max_episode_steps=max_steps)
