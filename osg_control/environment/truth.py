"""``TruthReadouts``: a skill env's readouts of the simulator's truth (arm joints, TCP pose,
facts, where a node is now), the skill success predicate on it and the step info, whatever
the plant: for scoring, labels and set-ups, never for deciding (that reads ``percept``).
The env supplies the world-state vector, its facts and the true 10-D state;
``SceneTruth`` does so for ``ArmEnv`` from its scene's hooks."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from osg_control.domain.frames import node_position
from osg_control.domain.spec import Node, SkillSpec
from osg_control.environment.scene_hooks import SceneHooks
from osg_control.environment.sensing import ArmSensors
from osg_control.environment.success import success_holds


class TruthReadouts:
    """The truth part of a skill env (its ``__init__`` sets the attributes below; it
    implements ``_true_world``, ``facts_of`` and ``true_state``)."""

    data: mujoco.MjData
    nodes: dict[str, Node]
    anchor_offsets: dict[str, np.ndarray]
    skill: SkillSpec | None
    _arm_qpos: slice | np.ndarray
    _tcp: int
    _gripper_cmd: float
    _steps: int
    _succeeded: bool

    def _true_world(self) -> np.ndarray:
        """The domain's world-state vector read from the simulator, a fresh array (the env's
        own; its step scores with it)."""
        raise NotImplementedError

    def world_state(self) -> np.ndarray:
        """The scene's true state beyond the robot (the domain's world-state vector): for
        scoring and labels, never for deciding (``percept().world`` is what the robot
        perceives)."""
        return self._true_world()

    def facts_of(self, world: np.ndarray) -> frozenset[str]:
        """The domain's facts that hold in a world-state vector."""
        raise NotImplementedError

    def true_state(self) -> np.ndarray:
        """Truth (scoring): the 10-D state of the simulator (the ``sim`` percept's state)."""
        raise NotImplementedError

    @property
    def arm_q(self) -> np.ndarray:
        """True arm joint positions [rad] (a copy): the simulator's, for scoring and the step
        info (what decides reads the encoders, ``percept().joints``)."""
        return self.data.qpos[self._arm_qpos].copy()

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """True TCP position [m] and rotation matrix: the simulator's truth, for scoring and
        set-ups (what decides reads ``percept``)."""
        return (
            self.data.site_xpos[self._tcp].copy(),
            self.data.site_xmat[self._tcp].reshape(3, 3).copy(),
        )

    def facts(self) -> frozenset[str]:
        """The world facts that hold now in the simulator (scoring; ``percept().facts`` is
        what the robot believes)."""
        return self.facts_of(self._true_world())

    def node_position(self, name: str) -> np.ndarray:
        """Where a node is in the world as reset (its anchor's true displacement applied)."""
        return node_position(self.nodes, name, self.anchor_offsets)

    def skill_success(
        self, skill: SkillSpec | None = None, world: np.ndarray | None = None
    ) -> bool:
        """The success predicate on the simulator's truth (scoring and Algorithm 1's
        labels): TCP within tolerance of beta, gripper state, world effect.

        Args:
            skill: the skill to check (default: the env's own).
            world: the current world state, if the caller has read it already.
        """
        skill = skill or self.skill
        if skill is None:
            return False
        facts = self.facts_of(self._true_world() if world is None else world)
        return self._truth_success(skill, facts)

    def _truth_success(self, skill: SkillSpec, facts: frozenset[str]) -> bool:
        """The success predicate with ``facts``: the true world's."""
        return success_holds(
            skill,
            self.nodes[skill.end],
            self.data.site_xpos[self._tcp],
            self._gripper_cmd,
            facts,
            self.node_position(skill.end),
        )

    def _info(
        self, world: np.ndarray | None = None, facts: frozenset[str] | None = None
    ) -> dict[str, Any]:
        """The step's information: ``world`` and ``world_facts`` are the simulator's truth,
        for scoring and for labelling scripted data, never for deciding (``percept``);
        ``facts``: ``world``'s, if the caller has them already."""
        world = self._true_world() if world is None else world
        facts = self.facts_of(world) if facts is None else facts
        return truth_info(world, facts, self._steps, self._succeeded, self.arm_q)


class SceneTruth(TruthReadouts, SceneHooks):
    """``TruthReadouts`` of ``ArmEnv``'s own scene: the world read by its ``read_world``
    hook, the true state by its simulated sensors."""

    sensors: ArmSensors

    def _true_world(self) -> np.ndarray:
        return self.read_world()

    def true_state(self) -> np.ndarray:
        return self.sensors.true_state(self.data, self._gripper_cmd)


def truth_info(
    world: np.ndarray, facts: frozenset[str], steps: int, success: bool, arm_q: np.ndarray
) -> dict[str, Any]:
    """A step's information on the simulator's truth, every env's (``SkillEnv``): the world
    vector and its facts, the steps since the start, whether the skill's success has held,
    the true arm joints. For scoring and labels, never for deciding."""
    return {
        "world": world,
        "world_facts": sorted(facts),
        "steps": steps,
        "success": success,
        "arm_q": arm_q,
    }
