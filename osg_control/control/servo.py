"""The arm's speed-capped joint drive, built into the MuJoCo model, and its speed watch.

The IK bounds each control step's joint motion by the URDF velocity limits, but a position
servo handed the whole step at once chases it with a velocity peak well above them (up to
2.7x). MuJoCo's position servo applies ``kp (target - q) - kv qdot``, i.e. a velocity servo
of gain ``kv`` toward the set-point ``(kp / kv) (target - q)``. Capping the stiffness term at
``SPEED_MARGIN * limit * kv`` caps that set-point below the limit: far from the target a
joint runs at the capped speed, near it the position servo takes over as before.

The drive is two actuators per joint (``add_speed_capped_drive``): the stiffness
``kp (target - q)`` with its force range at that cap, and the damping ``-kv qdot`` (a
velocity actuator at zero, ``DAMPING_SUFFIX``); the joint's actuator force range holds
their sum within the motor's effort, as the single servo's force range did. The force is
``clamp(clamp(kp (target - q), +-cap) - kv qdot, +-effort)``, the same law as clamping the
servo's target to within ``cap / kp`` of the joint before every physics substep (how it was
done in Python before), so MuJoCo runs a whole control step in one call. The two differ in
floating-point rounding only (the sum is formed in another order), and the implicit
integrator's velocity derivative is ``-kv`` in both.

The arm's inertial coupling still overshoots that set-point (up to 1.2x the limit under
full-speed commands), so the joint drive also saturates the speed, as an industrial arm's
joint controllers limit their joints' velocities: after a physics substep in which a joint ran
faster than its limit, ``saturate_joint_speeds`` sets its velocity to the limit and its
position to where the substep would have taken it at that speed. ``SpeedWatch`` reads every
substep's joint speeds from MuJoCo's sensor history (``add_speed_sensors``) after substeps
run in one call; when one exceeded a limit the env goes back to the start of the call, runs
up to that substep again, saturates and goes on, so the physics is bit for bit that of a
substep-by-substep loop that saturates after each substep.

A ramped target (interpolated across the substeps) was tried first: the servo follows a
ramp about ``kv / kp`` (16 ms) behind, and the IK, which starts each step from the measured
joints, lost that lag every step, a third of the arm's speed. Leading the ramp by the lag
restored the speed but overshot the limits by up to 1.6x when a step reversed a joint.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

SPEED_MARGIN = 0.8
"""The servo's velocity set-point cap as a fraction of the URDF limit: the arm's inertial
coupling makes a joint overshoot its set-point (the skills shipped before the limit peaked
at 1.23x the limit with a cap of 1.0 and at 0.99x with 0.8; the skills trained with it peak
at 0.80-0.95x, push-valve-open, pushing the valve lever, at 1.034x before the speed
saturation, full-speed +x commands at 1.20x; ``tools/joint_speeds.py``)."""
DAMPING_SUFFIX = "_damping"
"""Name suffix of a joint's damping actuator (the stiffness actuator has the joint's name)."""
SPEED_SENSOR_SUFFIX = "_speed"
"""Name suffix of a joint's velocity sensor with a history of the last substeps."""


def add_speed_capped_drives(
    spec: mujoco.MjSpec,
    joints: Sequence[str],
    kp: Sequence[float],
    kv: Sequence[float],
    effort: Sequence[float],
    speed_limit: Sequence[float] | np.ndarray,
) -> None:
    """Add the joints' drives to ``spec`` (see the module doc): first a stiffness actuator
    per joint, named after it (target in the joint's range, force capped at
    ``SPEED_MARGIN * speed_limit * kv``), then a damping actuator per joint
    (``-kv qdot``, named ``joint + DAMPING_SUFFIX``); each joint's actuator force range is
    ``+-effort``."""
    rows = list(zip(joints, kp, kv, effort, speed_limit, strict=True))
    for joint, gain, damping, _, limit in rows:
        cap = SPEED_MARGIN * limit * damping
        stiffness = spec.add_actuator(name=joint, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        stiffness.set_to_position(kp=gain, kv=0.0)
        stiffness.ctrlrange = spec.joint(joint).range
        stiffness.ctrllimited = True
        stiffness.forcerange = [-cap, cap]
        stiffness.forcelimited = True
    for joint, _, damping, limit_force, _ in rows:
        actuator = spec.add_actuator(
            name=joint + DAMPING_SUFFIX, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT
        )
        actuator.set_to_velocity(kv=damping)
        spec.joint(joint).actfrcrange = [-limit_force, limit_force]
        spec.joint(joint).actfrclimited = True


def uncap_drive(model: mujoco.MjModel, joints: Sequence[str]) -> None:
    """Lift the stiffness cap of ``joints``' drives in ``model`` (the unlimited servo, for
    comparison only: ``EnvConfig.limit_joint_speed=False``)."""
    for joint in joints:
        model.actuator_forcelimited[model.actuator(joint).id] = 0


def add_speed_sensors(spec: mujoco.MjSpec, joints: Sequence[str], samples: int) -> None:
    """Add a velocity sensor per joint keeping its last ``samples`` readings (one per
    physics substep: MuJoCo records each at the start of a substep, before integrating)."""
    for joint in joints:
        spec.add_sensor(
            name=joint + SPEED_SENSOR_SUFFIX,
            type=mujoco.mjtSensor.mjSENS_JOINTVEL,
            objtype=mujoco.mjtObj.mjOBJ_JOINT,
            objname=joint,
            nsample=samples,
        )


class SpeedWatch:
    """Each substep's peak ``|qdot| / limit`` over the joints, for the substeps just run in
    one ``mj_step`` call, read from the speed sensors' history and the current velocities.

    ``available`` is False when the model lacks the sensors or their history is shorter
    than ``substeps`` (the env then watches substep by substep).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        joints: Sequence[str],
        dofs: slice | np.ndarray,
        limits: np.ndarray,
        substeps: int,
    ) -> None:
        self._dofs = dofs
        self._inverse_limits = 1.0 / np.asarray(limits, dtype=float)
        self.available = False
        ids = [
            mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, joint + SPEED_SENSOR_SUFFIX)
            for joint in joints
        ]
        if min(ids) < 0 or any(int(model.sensor_history[i, 0]) < substeps for i in ids):
            return
        self.available = True
        self._samples = int(model.sensor_history[ids[0], 0])
        # A sensor's history: [header, cursor (the newest slot), times (n), values (n)].
        self._cursor = int(model.sensor_historyadr[ids[0]]) + 1
        self._values = np.array([int(model.sensor_historyadr[i]) + 2 + self._samples for i in ids])
        self._cache: dict[tuple[int, int], np.ndarray] = {}

    def ratios(self, data: mujoco.MjData, substeps: int) -> np.ndarray:
        """The peak speed ratio after each of the last ``substeps`` substeps, oldest first.

        A sample is read at the start of a substep: the newest ``substeps - 1`` samples are
        the velocities after the first ``substeps - 1``; the last is ``data.qvel``.
        """
        return np.append(self._during(data, substeps).max(axis=0), self.ratio_now(data))

    def peak(self, data: mujoco.MjData, substeps: int) -> float:
        """The largest of ``ratios(data, substeps)``: the peak over the call's substeps
        (the same maximum, without building the per-substep vector)."""
        during = self._during(data, substeps)  # empty for one substep
        return max(float(during.max(initial=0.0)), self.ratio_now(data))

    def _during(self, data: mujoco.MjData, substeps: int) -> np.ndarray:
        """The speed ratios (joints x substeps - 1) after the first ``substeps - 1``."""
        rows = self._rows(int(data.history[self._cursor]), substeps)
        return np.abs(data.history[rows]) * self._inverse_limits[:, None]

    def ratio_now(self, data: mujoco.MjData) -> float:
        """The peak speed ratio now (``data.qvel``): the last substep's (also without the
        sensors)."""
        return float((np.abs(data.qvel[self._dofs]) * self._inverse_limits).max())

    def _rows(self, newest: int, substeps: int) -> np.ndarray:
        """History indices (joints x substeps - 1) of the samples after the first
        ``substeps - 1`` substeps, when the newest sample is in slot ``newest``."""
        key = (newest, substeps)
        rows = self._cache.get(key)
        if rows is None:
            slots = (newest + np.arange(2 - substeps, 1)) % self._samples
            rows = self._cache[key] = self._values[:, None] + slots[None, :]
        return rows


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
