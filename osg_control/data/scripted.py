"""The paper's Algorithm 1: a scripted, deliberately noisy waypoint-following policy.

For each waypoint of a skill, for a fixed number of steps: while the TCP is farther than a
threshold ``~ N(mu_1, sigma_1^2)`` (or the waypoint's own ``reach``) from the waypoint, act
with the error ``target - current`` (position [m] and orientation [rad], clipped by the
env); else, if the gripper is not in the waypoint's state, switch it; else do nothing.
Every action gets ``N(mu_2, sigma_2^2)`` noise on its motion components (orientation noise
scaled by the ratio of the rotation and position bounds, 0.1/0.02 for the paper's); the
gripper component is left noise-free so that noise never toggles the gripper by itself.
"""

from __future__ import annotations

import numpy as np

from osg_control.control.rotations import quat_to_matrix, rotation_error
from osg_control.domain.spec import TOP_DOWN_QUAT, ScriptParams, SkillSpec
from osg_control.environment.actions import scale_into
from osg_control.environment.success import GRIPPER_CLOSED_CMD, GRIPPER_OPEN_CMD

_TOP_DOWN_ROT = quat_to_matrix(np.array(TOP_DOWN_QUAT))


class ScriptedPolicy:
    """Algorithm 1 for one skill; call ``reset`` at the start of every episode."""

    def __init__(
        self,
        skill: SkillSpec,
        rng: np.random.Generator,
        params: ScriptParams | None = None,
        *,
        bounds: np.ndarray,
    ) -> None:
        self.skill = skill
        self.bounds = np.asarray(bounds, dtype=float)
        """Per-step action bounds (the env's ``action_bounds``)."""
        ratio = self.bounds[3] / self.bounds[0]
        self._noise_scale = np.concatenate([np.ones(3), np.full(3, ratio)])
        """The motion noise's scale: orientation noise scaled by the bound ratio."""
        self.params = params or skill.script
        self.rng = rng
        self.threshold = 0.0
        self._step = 0
        self._ends = np.cumsum(skill.waypoint_budgets(self.params))
        """The step at which each waypoint's budget ends."""
        self._rotations = [
            _TOP_DOWN_ROT if w.orientation is None else quat_to_matrix(np.array(w.orientation))
            for w in skill.waypoints
        ]

    def reset(self) -> None:
        """Draw this episode's threshold and restart at the first waypoint."""
        p = self.params
        self.threshold = max(0.0, float(self.rng.normal(p.threshold_mean, p.threshold_std)))
        self._step = 0

    @property
    def done(self) -> bool:
        """Every waypoint's step budget is used up."""
        return self._step >= self._ends[-1]

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        """The noisy action for an observation (10-D, see ``osg_control.environment.arm_env``)."""
        index = min(
            int(np.searchsorted(self._ends, self._step, side="right")),
            len(self.skill.waypoints) - 1,
        )
        waypoint = self.skill.waypoints[index]
        self._step += 1
        action = np.zeros(7)
        position_error = np.asarray(waypoint.position) - obs[:3]
        wanted = GRIPPER_OPEN_CMD if waypoint.gripper == "open" else GRIPPER_CLOSED_CMD
        reach = self.threshold if waypoint.reach is None else waypoint.reach
        if np.linalg.norm(position_error) > reach:
            action[:3] = scale_into(position_error, self.bounds[0])
            action[3:6] = scale_into(
                rotation_error(quat_to_matrix(obs[3:7]), self._rotations[index]), self.bounds[3]
            )
        elif obs[7] != wanted:
            action[6] = wanted
        noise = self.rng.normal(self.params.noise_mean, self.params.noise_std, 6)
        noise *= self._noise_scale
        action[:6] += noise
        return np.clip(action, -self.bounds, self.bounds)
