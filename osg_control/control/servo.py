"""A velocity-limited position servo: the arm's joint targets within the URDF speed limits.

The IK bounds each control step's joint motion by the URDF velocity limits, but a position
servo handed the whole step at once chases it with a velocity peak well above them (up to
2.7x). MuJoCo's position servo applies ``kp (target - q) - kv qdot``, i.e. a velocity servo
of gain ``kv`` toward the set-point ``(kp / kv) (target - q)``. Clamping the target on every
physics substep to within ``SPEED_MARGIN * limit * kv / kp`` of the measured joint caps that
set-point below the limit: far from the target a joint runs at the capped speed, near it
the position servo takes over as before.

The arm's inertial coupling still overshoots that set-point (up to 1.2x the limit under
full-speed commands), so the joint drive also saturates the speed, as the Franka's joint
controllers limit their joints' velocities: after a physics substep in which a joint ran
faster than its limit, ``saturate_joint_speeds`` sets its velocity to the limit and its
position to where the substep would have taken it at that speed. On a substep in which no
joint exceeds its limit nothing is written, so such physics is bit for bit that of the servo
alone.

A ramped target (interpolated across the substeps) was tried first: the servo follows a
ramp about ``kv / kp`` (16 ms) behind, and the IK, which starts each step from the measured
joints, lost that lag every step, a third of the arm's speed. Leading the ramp by the lag
restored the speed but overshot the limits by up to 1.6x when a step reversed a joint.
"""

from __future__ import annotations

import mujoco
import numpy as np

SPEED_MARGIN = 0.8
"""The servo's velocity set-point cap as a fraction of the URDF limit: the arm's inertial
coupling makes a joint overshoot its set-point (the skills shipped before the limit peaked
at 1.23x the limit with a cap of 1.0 and at 0.99x with 0.8; the skills trained with it peak
at 0.80-0.95x, push-valve-open, pushing the valve lever, at 1.034x before the speed
saturation, full-speed +x commands at 1.20x; ``tools/joint_speeds.py``)."""


def servo_speed_band(
    model: mujoco.MjModel, actuators: np.ndarray | slice, velocity_limits: np.ndarray
) -> np.ndarray:
    """How far [rad] a position actuator's target may lead its joint (n,): the distance at
    which its velocity set-point reaches ``SPEED_MARGIN`` of the limit, ``kv / kp`` times it
    (MuJoCo's ``kp = gainprm[0]``, ``kv = -biasprm[2]``)."""
    lead_time = -model.actuator_biasprm[actuators, 2] / model.actuator_gainprm[actuators, 0]
    return SPEED_MARGIN * np.asarray(velocity_limits) * lead_time


def velocity_limited_target(target: np.ndarray, joints: np.ndarray, band: np.ndarray) -> np.ndarray:
    """``target`` clamped to within ``band`` of the measured ``joints`` (see the module doc);
    ``np.clip``'s arithmetic without its wrapper's overhead, which on the physics loop's
    7-vectors cost more than the clamp (2.9 against 1.9 us per substep)."""
    return np.minimum(np.maximum(target, joints - band), joints + band)


def saturate_joint_speeds(
    data: mujoco.MjData,
    qpos: np.ndarray | slice,
    dofs: np.ndarray | slice,
    limits: np.ndarray,
    timestep: float,
) -> None:
    """Saturate the joints' velocities (``dofs``, hinges at ``qpos``) to ``+-limits`` after a
    substep, moving each saturated joint back to where the substep would have taken it at
    the limit: MuJoCo's Euler and implicit integrators advance ``q`` by ``timestep * qdot``
    with the new ``qdot``."""
    velocity = data.qvel[dofs]
    saturated = np.minimum(np.maximum(velocity, -limits), limits)
    data.qpos[qpos] -= timestep * (velocity - saturated)
    data.qvel[dofs] = saturated
