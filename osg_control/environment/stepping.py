"""The physics of one control step of the arm: the substeps toward a joint target, with
the drive's speed cap and the speed saturation of ``control.servo``, and a divergence
check; and ``MujocoActuation``, the ``skill_step.Actuation`` of a scene simulated here.
``ArmEnv`` runs every step and joint-reset step through them."""

from __future__ import annotations

import mujoco
import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.control.divergence import DivergenceWatch
from osg_control.control.servo import SpeedWatch, saturate_joint_speeds
from osg_control.environment.skill_step import Actuated
from osg_control.environment.success import GRIPPER_OPEN_CMD

_STEP_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
"""The state a control step is rerun from: everything ``mj_step`` reads."""


class ArmControlStep:
    """Runs a control step's substeps on ``model``/``data`` toward an arm joint target.

    Args:
        model, data: the scene.
        robot: the arm (its joints and their speed limits).
        arm_qpos, arm_dof, arm_act: the arm joints' qpos and dof addresses and actuators.
        n_substeps: physics substeps per control step.
        limit_joint_speed: saturate a joint speed over its limit (False: only measure).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        robot: RobotDescription,
        arm_qpos: slice | np.ndarray,
        arm_dof: slice | np.ndarray,
        arm_act: slice | np.ndarray,
        n_substeps: int,
        limit_joint_speed: bool,
    ) -> None:
        self.model, self.data = model, data
        self._arm_qpos, self._arm_dof, self._arm_act = arm_qpos, arm_dof, arm_act
        self.n_substeps = n_substeps
        self.limit_joint_speed = limit_joint_speed
        self._velocity_limits = np.array(robot.arm.velocity)
        self._speed_watch = SpeedWatch(
            model, robot.arm.names, arm_dof, self._velocity_limits, n_substeps
        )
        self._step_start = np.empty(mujoco.mj_stateSize(model, _STEP_STATE))
        self._watch = DivergenceWatch(data)

    def run(self, arm_target: np.ndarray) -> tuple[str | None, float]:
        """One control step toward ``arm_target``: the failure reason if the simulation
        diverged (else None) and the peak joint speed ratio (|speed| / limit) over its
        substeps.

        MuJoCo runs the substeps in one call and the speed sensors' history gives each
        one's joint speeds; when one exceeded its limit (with ``limit_joint_speed``), the
        physics goes back to the call's start, runs up to that substep again, saturates the
        speeds and goes on with the substeps left.
        """
        watch = self._watch
        watch.start()
        self.data.ctrl[self._arm_act] = arm_target
        if not self._speed_watch.available:
            return self._saturating_substeps(watch)
        peak, left = 0.0, self.n_substeps
        while left:
            mujoco.mj_getState(self.model, self.data, self._step_start, _STEP_STATE)
            mujoco.mj_step(self.model, self.data, left)
            fastest = self._speed_watch.peak(self.data, left)
            if fastest <= 1.0 or not self.limit_joint_speed:
                peak = max(peak, fastest)
                break
            ratios = self._speed_watch.ratios(self.data, left)
            first = int(np.argmax(ratios > 1.0)) + 1  # substeps up to the first too fast one
            mujoco.mj_setState(self.model, self.data, self._step_start, _STEP_STATE)
            mujoco.mj_step(self.model, self.data, first)
            peak = max(peak, float(ratios[: first - 1].max(initial=0.0)), self._saturate())
            left -= first
        return watch.check(), peak

    def _saturate(self) -> float:
        """Saturate the arm's joint speeds (``servo.saturate_joint_speeds``); returns the peak
        speed ratio after it."""
        saturate_joint_speeds(
            self.data, self._arm_qpos, self._arm_dof, self._velocity_limits, self.model.opt.timestep
        )
        return self._speed_watch.ratio_now(self.data)

    def _saturating_substeps(self, watch: DivergenceWatch) -> tuple[str | None, float]:
        """``run`` substep by substep, for a model without the speed sensors."""
        peak = 0.0
        for _ in range(self.n_substeps):
            mujoco.mj_step(self.model, self.data)
            fastest = self._speed_watch.ratio_now(self.data)
            if self.limit_joint_speed and fastest > 1.0:
                fastest = self._saturate()
            peak = max(peak, fastest)
        return watch.check(), peak


class MujocoActuation:
    """``skill_step.Actuation`` of a scene simulated here: the gripper actuator set from the
    latched command, then ``ArmControlStep`` toward the IK's joint targets; it keeps the
    peak joint speed ratio (``|speed| / limit``) since ``peak`` was last zeroed.

    Args:
        control_step: the arm's control step on the scene.
        gripper_act: the gripper actuator's index.
        finger_open: its target when open (0 when closed).
    """

    def __init__(self, control_step: ArmControlStep, gripper_act: int, finger_open: float) -> None:
        self.control_step = control_step
        self._gripper_act = gripper_act
        self._finger_open = finger_open
        self.peak = 0.0
        """Peak joint speed ratio over every substep run since it was last zeroed."""

    def apply(self, command: np.ndarray, gripper_cmd: float) -> Actuated:
        """The gripper's target, then one control step toward the joint targets
        ``command``; ``info["joint_speed_ratio"]``: the step's peak speed ratio."""
        self.control_step.data.ctrl[self._gripper_act] = (
            self._finger_open if gripper_cmd == GRIPPER_OPEN_CMD else 0.0
        )
        failure, peak = self.simulate(command)
        return Actuated(failure, info={"joint_speed_ratio": peak})

    def halt(self, failure: str) -> Actuated:
        """Nothing simulated: a speed ratio of 0."""
        return Actuated(failure, info={"joint_speed_ratio": 0.0})

    def simulate(self, arm_target: np.ndarray) -> tuple[str | None, float]:
        """``ArmControlStep.run`` (a step's or a joint reset's), its peak recorded."""
        failure, peak = self.control_step.run(arm_target)
        self.peak = max(self.peak, peak)
        return failure, peak
