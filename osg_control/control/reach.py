"""Whether an arm reaches a TCP pose: mink's differential IK run from a start posture.

Each step solves mink's QP (frame task on the TCP site, a low-weight posture task, joint
position and velocity limits) for one control period and integrates it, as the env's
controller does (optionally walking the target along the straight line, as bounded actions
do), so a pose counts as reached only along a path the controller could take
from the start posture. Used to check a robot's placement against a scene's nodes before
any episode.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

CONTROL_PERIOD = 0.05
"""The IK's integration step [s] (a 20 Hz control loop)."""


@dataclass(frozen=True)
class Reach:
    """The outcome of ``reach_pose``.

    Attributes:
        q: the final joint configuration [rad].
        position_error: the TCP's distance from the target [m].
        orientation_error: the TCP's rotation angle from the target [rad].
        path: the configuration after each step [rad] (steps x joints), ending at ``q``.
    """

    q: np.ndarray
    position_error: float
    orientation_error: float
    path: np.ndarray

    def reached(self, position_tol: float = 1e-3, orientation_tol: float = 1e-2) -> bool:
        """Whether both errors are within ``position_tol`` [m] and ``orientation_tol`` [rad]."""
        return self.position_error <= position_tol and self.orientation_error <= orientation_tol


def reach_pose(
    model: mujoco.MjModel,
    site: str,
    position: Sequence[float],
    quat: Sequence[float],
    start_q: np.ndarray,
    velocity_limits: dict[str, float],
    steps: int = 400,
    *,
    orientation_cost: float = 0.5,
    posture_cost: float = 1e-3,
    max_step: float | None = None,
    stop_within: tuple[float, float] | None = None,
) -> Reach:
    """Drive ``model``'s (an arm-only model's) ``site`` toward the pose (``position`` [m],
    ``quat`` w x y z, in the model's world frame) from ``start_q`` for ``steps`` control
    periods; the posture task pulls toward ``start_q``.

    Args:
        velocity_limits: each joint's velocity limit [rad/s], by joint name.
        max_step: the most the frame task's target position moves per step [m]: it walks
            the straight line from the start's TCP to ``position``, as an env's bounded
            actions do. None sets the goal at once (the IK's own path, limited only by the
            joints' speeds, may then swing wide of the line).

    Raises:
        ValueError: for ``steps`` below 1, ``max_step`` not positive, a ``start_q`` of the
            wrong size or a non-finite target.
    """
    import mink

    if steps < 1 or np.shape(start_q) != (model.nq,) or (max_step is not None and max_step <= 0):
        raise ValueError(
            f"reach_pose: steps {steps} < 1, max_step {max_step} <= 0 or start_q not of "
            f"shape ({model.nq},)"
        )
    if not (np.all(np.isfinite(position)) and np.all(np.isfinite(quat))):
        raise ValueError(f"reach_pose: non-finite target {position}, {quat}")
    configuration = mink.Configuration(model, np.asarray(start_q, dtype=float))
    frame = mink.FrameTask(
        site, "site", position_cost=1.0, orientation_cost=orientation_cost, lm_damping=1e-6
    )
    rotation = mink.SO3(np.asarray(quat, dtype=float))
    goal = np.asarray(position, dtype=float)
    target = mink.SE3.from_rotation_and_translation(rotation, goal)
    waypoint = configuration.get_transform_frame_to_world(site, "site").translation()
    posture = mink.PostureTask(model, cost=posture_cost)
    posture.set_target(np.asarray(start_q, dtype=float))
    limits = [
        mink.ConfigurationLimit(model, gain=0.95),
        mink.VelocityLimit(model, velocity_limits),
    ]
    path = np.empty((steps, model.nq))
    for step in range(steps):
        if max_step is None:
            waypoint = goal
        else:
            offset = goal - waypoint
            distance = float(np.linalg.norm(offset))
            waypoint = goal if distance <= max_step else waypoint + offset * (max_step / distance)
        frame.set_target(mink.SE3.from_rotation_and_translation(rotation, waypoint))
        velocity = mink.solve_ik(
            configuration, [frame, posture], CONTROL_PERIOD, "daqp", 1e-9, limits=limits
        )
        configuration.integrate_inplace(velocity, CONTROL_PERIOD)
        path[step] = configuration.q
        if stop_within is not None and waypoint is goal:
            errors = _errors(configuration, site, target)
            if errors[0] <= stop_within[0] and errors[1] <= stop_within[1]:
                return Reach(configuration.q.copy(), *errors, path[: step + 1])
    return Reach(configuration.q.copy(), *_errors(configuration, site, target), path)


def _errors(configuration: Any, site: str, target: Any) -> tuple[float, float]:
    """The site's distance [m] and rotation angle [rad] from ``target``."""
    reached = configuration.get_transform_frame_to_world(site, "site")
    offset = reached.translation() - target.translation()
    turn = (reached.rotation().inverse() @ target.rotation()).log()
    return float(np.linalg.norm(offset)), float(np.linalg.norm(turn))
