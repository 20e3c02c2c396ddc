"""Whether an arm reaches a TCP pose: mink's differential IK run from a start posture.

Each step solves mink's QP (frame task on the TCP site, a low-weight posture task, joint
position and velocity limits) for one control period and integrates it, as the env's
controller does, so a pose counts as reached only along a path the controller could take
from the start posture. Used to check a robot's placement against a scene's nodes before
any episode.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

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
    """

    q: np.ndarray
    position_error: float
    orientation_error: float

    def reached(self, position_tol: float = 1e-3, orientation_tol: float = 1e-2) -> bool:
        """Whether both errors are within ``position_tol`` [m] and ``orientation_tol`` [rad]."""
        return self.position_error <= position_tol and self.orientation_error <= orientation_tol


def base_frame_target(
    position: Sequence[float],
    quat: Sequence[float],
    base_pos: Sequence[float],
    base_quat: Sequence[float],
) -> tuple[np.ndarray, np.ndarray]:
    """A world TCP pose (position [m], quaternion w x y z) in the frame of a robot base placed
    at ``base_pos``, ``base_quat`` in the world."""
    import mink

    base = mink.SE3.from_rotation_and_translation(
        mink.SO3(np.asarray(base_quat, float)), np.asarray(base_pos, float)
    )
    world = mink.SE3.from_rotation_and_translation(
        mink.SO3(np.asarray(quat, float)), np.asarray(position, float)
    )
    local = base.inverse() @ world
    return np.array(local.translation()), np.array(local.rotation().wxyz)


def reach_pose(
    model: mujoco.MjModel,
    site: str,
    position: Sequence[float],
    quat: Sequence[float],
    start_q: np.ndarray,
    velocity_limits: dict[str, float],
    steps: int = 400,
    orientation_cost: float = 0.5,
    posture_cost: float = 1e-3,
) -> Reach:
    """Drive ``model``'s (an arm-only model's) ``site`` toward the pose (``position`` [m],
    ``quat`` w x y z, in the model's world frame) from ``start_q`` for ``steps`` control
    periods; the posture task pulls toward ``start_q``.

    Args:
        velocity_limits: each joint's velocity limit [rad/s], by joint name.
    """
    import mink

    configuration = mink.Configuration(model, np.asarray(start_q, dtype=float))
    frame = mink.FrameTask(
        site, "site", position_cost=1.0, orientation_cost=orientation_cost, lm_damping=1e-6
    )
    target = mink.SE3.from_rotation_and_translation(
        mink.SO3(np.asarray(quat, dtype=float)), np.asarray(position, dtype=float)
    )
    frame.set_target(target)
    posture = mink.PostureTask(model, cost=posture_cost)
    posture.set_target(np.asarray(start_q, dtype=float))
    limits = [
        mink.ConfigurationLimit(model, gain=0.95),
        mink.VelocityLimit(model, velocity_limits),
    ]
    for _ in range(steps):
        velocity = mink.solve_ik(
            configuration, [frame, posture], CONTROL_PERIOD, "daqp", 1e-9, limits=limits
        )
        configuration.integrate_inplace(velocity, CONTROL_PERIOD)
    reached = configuration.get_transform_frame_to_world(site, "site")
    offset = reached.translation() - target.translation()
    turn = (reached.rotation().inverse() @ target.rotation()).log()
    return Reach(configuration.q.copy(), float(np.linalg.norm(offset)), float(np.linalg.norm(turn)))
