"""``KitchenStepActuation``: the ``skill_step.Actuation`` of a caller's FrankaKitchen-v1:
each control step is the env's own ``step`` with the 9-D action ``franka.arm.ServoCommand``
made (its reward, termination, time limit and task completion as the library ships them).
It keeps the observation and info the env returned last: the ``env`` perception reads
them."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from osg_control.control.divergence import DivergenceWatch
from osg_control.environment.skill_step import Actuated
from osg_control.franka.perception import observation_vector


class KitchenStepActuation:
    """Steps the caller's env (``env``: any wrapper of a FrankaKitchen-v1; ``data``: its
    simulator's state, watched for divergence)."""

    def __init__(self, env: Any, data: mujoco.MjData) -> None:
        self.env = env
        self.data = data
        self.observation: np.ndarray | None = None
        """The env's latest 59-D ``observation`` array (None before its first reset)."""
        self.env_info: dict[str, Any] = {}
        """The info the env returned last."""

    def reset(self, seed: int | None) -> None:
        """The env's own ``reset``, its observation and info kept."""
        obs, env_info = self.env.reset(seed=seed)
        self.observation = observation_vector(obs)
        self.env_info = dict(env_info)

    def apply(self, command: np.ndarray, gripper_cmd: float) -> Actuated:
        """The env's ``step`` with the 9-D action ``command`` (its fingers' part already set
        from ``gripper_cmd`` by ``ServoCommand``); its own reward, ``terminated`` and
        ``truncated``, and ``info`` keys ``env_reward`` and ``env_info``."""
        watch = DivergenceWatch(self.data)
        obs, env_reward, terminated, truncated, env_info = self.env.step(command)
        self.observation = observation_vector(obs)
        self.env_info = dict(env_info)
        return Actuated(
            watch.check(),
            float(env_reward),
            bool(terminated),
            bool(truncated),
            {"env_reward": float(env_reward), "env_info": self.env_info},
        )

    def halt(self, failure: str) -> Actuated:
        """The env not stepped: no reward of its own, its last info kept."""
        return Actuated(failure, info={"env_reward": 0.0, "env_info": self.env_info})
