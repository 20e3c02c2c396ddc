"""``StartPlacement``: how ``ArmEnv``'s reset puts a sampled start in place: the arm
teleported by IK, the scene's world and gripper set, the start refused if the robot is in
collision, contacts settled."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from osg_control.control.divergence import DivergenceWatch
from osg_control.control.ik import DiffIKController, solve_ik
from osg_control.control.robot_model import HOME_KEY
from osg_control.environment.scene_hooks import SceneHooks
from osg_control.environment.success import GRIPPER_CLOSED_CMD, GRIPPER_OPEN_CMD
from osg_control.errors import SimulationError


class StartPlacement(SceneHooks):
    """The start placement part of ``ArmEnv`` (``ArmEnv.__init__`` sets the attributes
    below)."""

    model: mujoco.MjModel
    data: mujoco.MjData
    ik: DiffIKController
    _arm_qpos: slice | np.ndarray
    _arm_act: slice | np.ndarray
    _finger_qpos: np.ndarray
    _finger_open: float
    _gripper_act: int
    _gripper_cmd: float
    _robot_bodies: set[int]

    def _place(
        self,
        pos: np.ndarray,
        rot: np.ndarray,
        gripper: str,
        holding: str | None,
        world: dict[str, Any],
        facts: frozenset[str],
    ) -> bool:
        """Teleport the arm (IK) and the world; return False if the start is in collision."""
        mujoco.mj_resetDataKeyframe(self.model, self.data, self.model.key(HOME_KEY).id)
        q, converged = solve_ik(self.ik, np.array(self.robot.home_q), pos, rot, iterations=300)
        if not converged:
            return False
        self.data.qpos[self._arm_qpos] = q
        self.data.ctrl[self._arm_act] = q
        mujoco.mj_kinematics(self.model, self.data)
        self.place_world(world, facts, holding)
        closed = gripper == "closed" or holding is not None
        finger = self.finger_opening(holding) if holding else self._finger_open
        self.data.qpos[self._finger_qpos] = finger if (holding or not closed) else 0.0
        self._gripper_cmd = GRIPPER_CLOSED_CMD if closed else GRIPPER_OPEN_CMD
        self.data.ctrl[self._gripper_act] = 0.0 if closed else self._finger_open
        mujoco.mj_forward(self.model, self.data)
        if self._robot_in_collision(allowed_geoms=self.held_geoms(holding)):
            return False
        self._settle(0.1)
        return not self._robot_in_collision(allowed_geoms=self.held_geoms(holding))

    def _robot_in_collision(self, allowed_geoms: set[int]) -> bool:
        for contact in self.data.contact[: self.data.ncon]:
            bodies = {self.model.geom_bodyid[contact.geom1], self.model.geom_bodyid[contact.geom2]}
            robot = bodies & self._robot_bodies
            if not robot or len(robot) == 2:
                continue
            if {contact.geom1, contact.geom2} & allowed_geoms:
                continue
            if contact.dist < -0.002:
                return True
        return False

    def _settle(self, seconds: float) -> None:
        """Let contacts settle with the arm servoed in place.

        Raises:
            SimulationError: the physics diverged (e.g. a start placed inside the furniture).
        """
        watch = DivergenceWatch(self.data)
        mujoco.mj_step(self.model, self.data, round(seconds / self.model.opt.timestep))
        diverged = watch.check()
        if diverged is not None:
            raise SimulationError(f"{diverged} while placing the start")
