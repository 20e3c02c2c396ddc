"""Gymnasium ids of the installed domains' environments, registered on ``import osg_control``.

A domain announces its env with an entry point in the ``osg_control.envs`` group: the name
is the Gymnasium id, the value the env class (``module:Class``), e.g. ``osg/Kitchen-v0`` in
``pyproject.toml``. Reading entry points imports nothing, so registering costs only
Gymnasium's import; MuJoCo and the domain load on the first ``gymnasium.make``.
"""

from __future__ import annotations

from importlib.metadata import entry_points

ENV_ENTRY_POINT_GROUP = "osg_control.envs"
MAX_EPISODE_STEPS = 200
"""``max_episode_steps`` of every id: ``EnvConfig.max_steps``, above every skill's own budget,
which the env enforces itself when made with ``skill=``."""
ENV_CHECKER = False
"""Gymnasium's passive env checker is left off for these ids: when the first ``reset`` is
refused (an ``EnvOptionError``), the checker (gymnasium 1.x) keeps no data of it and the
next good reset's first ``step`` raises ``TypeError``. The envs' own tests check the API
(``gymnasium.utils.env_checker.check_env``)."""


def installed_envs() -> dict[str, str]:
    """Gymnasium id -> entry point of every installed domain's env."""
    return {point.name: point.value for point in entry_points(group=ENV_ENTRY_POINT_GROUP)}


def register_envs() -> None:
    """Register every installed env with Gymnasium (an id already registered is kept)."""
    from gymnasium.envs.registration import register, registry

    for env_id, entry_point in installed_envs().items():
        if env_id not in registry:
            register(
                env_id,
                entry_point=entry_point,
                max_episode_steps=MAX_EPISODE_STEPS,
                disable_env_checker=not ENV_CHECKER,
            )
