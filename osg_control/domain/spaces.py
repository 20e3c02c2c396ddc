"""The paper's state and action as declared once: their sizes, the default action bounds, a
robot's observation bounds, and the check that a domain's env has the spaces its ``Domain``
declares.

Everything else derives from here or from the ``Domain`` (``Domain.action_bounds``,
``Domain.perceptions``, ``Domain.observation_bounds``): the env's spaces, training's action
scale, the data set schema, Minari's and LeRobot's exported spaces. The ``Domain`` wraps its
env factory in ``CheckedEnvFactory``, so an env that disagrees with its domain is refused
when it is built (``EnvMismatchError``), before any episode.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.errors import DomainError

OBS_DIM = 10
"""The paper's state: TCP position (3), quaternion (4), gripper command, grip force, finger
distance."""
ACTION_DIM = 7
"""The paper's action: relative TCP position (3) and rotation vector (3), gripper command."""
PAPER_ACTION_BOUNDS: tuple[float, ...] = (0.02, 0.02, 0.02, 0.1, 0.1, 0.1, 1.0)
"""The paper's per-step bound of each action component (2 cm, 0.1 rad, the gripper's
[-1, 1]): a ``Domain``'s default ``action_bounds``."""
_POSE_HIGH = (2.0, 2.0, 2.0, 1.0, 1.0, 1.0, 1.0, 1.0)
"""TCP position within 2 m of the base (reach under 1 m, plus noise), a unit quaternion and
the gripper command's [-1, 1]."""
WIDTH_SLACK = 0.02
"""Slack [m] on the finger distance's bound beyond the gripper's opening (contact
penetration)."""


class EnvMismatchError(DomainError):
    """A domain's env does not have the spaces, perceptions or methods its ``Domain``
    declares (raised when the env is built)."""


def observation_bounds(robot: RobotDescription) -> tuple[np.ndarray, np.ndarray]:
    """The 10-D state's bounds with ``robot``'s grip force [N] and finger opening [m]."""
    high = np.array([*_POSE_HIGH, robot.gripper.force, robot.gripper.max_opening + WIDTH_SLACK])
    low = -high
    low[8], low[9] = 0.0, -0.01
    return low, high


def unbounded_observation() -> tuple[np.ndarray, np.ndarray]:
    """The bounds of an env that drives its own arm and reports none (``robot`` None)."""
    return np.full(OBS_DIM, -np.inf), np.full(OBS_DIM, np.inf)


@dataclass(frozen=True)
class CheckedEnvFactory:
    """A domain's env factory that checks every env it builds against the domain.

    Attributes:
        factory: the domain's own ``make_env``.
        domain: the domain's name (for the error).
        action_bounds: ``Domain.action_bounds``.
        perceptions: ``Domain.perceptions``.
    """

    factory: Callable[..., Any]
    domain: str
    action_bounds: tuple[float, ...]
    perceptions: tuple[str, ...]

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        env = self.factory(*args, **kwargs)
        check_env(env, self.domain, self.action_bounds, self.perceptions)
        return env


def check_env(
    env: Any, domain: str, action_bounds: tuple[float, ...], perceptions: tuple[str, ...]
) -> None:
    """Check a domain's env implements ``SkillEnv`` with the paper's spaces, the domain's
    action bounds and at least the domain's perceptions.

    Raises:
        EnvMismatchError: naming the domain, the env and what differs.
    """
    from osg_control.domain.contract import missing_members

    where = f"domain {domain!r}: its env {type(env).__name__}"
    missing = missing_members(env)
    if missing:
        raise EnvMismatchError(f"{where} lacks the SkillEnv members {missing}")
    bounds = np.asarray(action_bounds, dtype=float)
    space = env.action_space
    if space.shape != (ACTION_DIM,) or not (
        np.array_equal(space.high, bounds) and np.array_equal(space.low, -bounds)
    ):
        raise EnvMismatchError(
            f"{where} has the action space {space}, not the domain's action_bounds "
            f"{list(action_bounds)}"
        )
    if not np.array_equal(np.asarray(env.action_bounds, dtype=float), bounds):
        raise EnvMismatchError(
            f"{where} clips to {list(env.action_bounds)}, not the domain's action_bounds "
            f"{list(action_bounds)}"
        )
    if env.observation_space.shape != (OBS_DIM,):
        raise EnvMismatchError(
            f"{where} observes {env.observation_space.shape}, not the paper's ({OBS_DIM},)"
        )
    unsupported = sorted(set(perceptions) - set(env.perceptions))
    if unsupported:
        raise EnvMismatchError(
            f"{where} does not simulate the domain's perceptions {unsupported} "
            f"(it simulates {list(env.perceptions)})"
        )
