"""The arm's simulated sensors: the 10-D state a perception gives, from the simulator.

``ArmSensors`` reads what the robot measures of itself: the TCP pose (true, with the
paper's noise on its position, or by forward kinematics of noisy joint encoders on a
scratch copy of the model), the latched gripper command, the gripper motor's force and the
finger width (with its own noise). The world part of a percept is the domain's
(``ArmEnv.detect_world`` over ``perception.sensors.noisy_world``).
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from osg_control.domain.spec import TOP_DOWN_QUAT
from osg_control.perception.spec import PerceptionSpec


class ArmSensors:
    """Encoders, gripper and TCP readouts of one arm in one model.

    Args:
        model: the compiled scene.
        arm_qpos: the arm joints' qpos addresses (a slice or an index array).
        finger_qpos: the finger joints' qpos addresses.
        gripper_actuator: the gripper actuator's id (its force is the grip force).
        tcp_site: the TCP site's id.
        width_scale: finger width [m] per unit of the finger joints' summed positions.
        reports_force: whether the gripper reports its force (else the state reads 0 N).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        arm_qpos: slice | np.ndarray,
        finger_qpos: np.ndarray,
        gripper_actuator: int,
        tcp_site: int,
        width_scale: float = 1.0,
        reports_force: bool = True,
    ) -> None:
        self.model = model
        self.arm_qpos = arm_qpos
        self.finger_qpos = finger_qpos
        self.gripper_actuator = gripper_actuator
        self.tcp_site = tcp_site
        self.width_scale = width_scale
        self.reports_force = reports_force
        self._fk: mujoco.MjData | None = None

    def true_state(self, data: mujoco.MjData, gripper_cmd: float) -> np.ndarray:
        """The exact 10-D state (the simulator's TCP site)."""
        return self._state(data, data, gripper_cmd, self._width(data))

    def _width(self, data: mujoco.MjData) -> float:
        """The true finger width [m]: the finger joints' summed positions, scaled."""
        return float(data.qpos[self.finger_qpos].sum()) * self.width_scale

    def perceived(
        self,
        data: mujoco.MjData,
        gripper_cmd: float,
        spec: PerceptionSpec,
        rng: np.random.Generator,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The perceived 10-D state and arm joints under ``spec``: the TCP by forward
        kinematics of the encoders (with their noise), the finger width with its noise, then
        the paper's noise on the TCP position, if any; draws nothing for an exact sensor."""
        joints = self.encoders(data, spec, rng)
        if spec.joint_noise == 0.0 and spec.finger_noise == 0.0:
            state = self.true_state(data, gripper_cmd)
        else:
            if self._fk is None:
                self._fk = mujoco.MjData(self.model)
            self._fk.qpos[self.arm_qpos] = joints
            mujoco.mj_kinematics(self.model, self._fk)
            fingers = self._width(data) + float(rng.normal(0.0, spec.finger_noise))
            state = self._state(self._fk, data, gripper_cmd, fingers)
        if spec.tcp_noise > 0:
            state[:3] += rng.normal(0.0, spec.tcp_noise, 3)
        return state, joints

    def encoders(
        self, data: mujoco.MjData, spec: PerceptionSpec, rng: np.random.Generator
    ) -> np.ndarray:
        """The arm joints [rad] as the encoders read them, with ``spec``'s encoder noise
        (draws nothing for exact encoders)."""
        joints = np.array(data.qpos[self.arm_qpos], dtype=float)
        if spec.joint_noise > 0:
            joints += rng.normal(0.0, spec.joint_noise, joints.shape)
        return joints

    def _state(
        self, pose: mujoco.MjData, data: mujoco.MjData, gripper_cmd: float, fingers: float
    ) -> np.ndarray:
        """The 10-D state with the TCP of ``pose`` and the gripper of ``data``."""
        force = (
            abs(float(data.actuator_force[self.gripper_actuator])) if self.reports_force else 0.0
        )
        site = self.tcp_site
        return tcp_state(pose.site_xpos[site], pose.site_xmat[site], gripper_cmd, force, fingers)


def tcp_state(
    position: np.ndarray,
    rotation: np.ndarray,
    gripper_cmd: float,
    force: float,
    width: float,
    reference: Any = None,
) -> np.ndarray:
    """The 10-D state ``[x, y, z, qw, qx, qy, qz, gripper command, grip force, finger
    width]`` of a TCP at ``position`` [m] with ``rotation`` (a 3x3 matrix, or its 9 values),
    the quaternion in the hemisphere of ``reference`` (``w, x, y, z``; default
    ``TOP_DOWN_QUAT``: ``canonical_quat``)."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.asarray(rotation, dtype=float).reshape(9))
    quat = canonical_quat(quat) if reference is None else canonical_quat(quat, reference)
    return np.concatenate([position, quat, [gripper_cmd, force, width]])


_TOP_DOWN = np.array(TOP_DOWN_QUAT)


def canonical_quat(quat_wxyz: np.ndarray, reference: Any = _TOP_DOWN) -> np.ndarray:
    """Flip a quaternion's sign into the hemisphere of ``reference`` (``w, x, y, z``;
    default ``TOP_DOWN_QUAT``): the state's orientation is one of the two signs, always the
    same for nearby orientations."""
    return -quat_wxyz if float(np.dot(quat_wxyz, reference)) < 0 else quat_wxyz
