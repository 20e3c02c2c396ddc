"""The adapter: a caller's FrankaKitchen-v1 with the paper's 10-D state and 7-D TCP action.

Wraps an env made with ``gymnasium.make("FrankaKitchen-v1", tasks_to_complete=[...])``
(any of its options, any wrapper of the caller's); its ``step``, reward, observation noise,
time limit and task completion run as the library ships them: the adapter only chooses
the 9-D action. The step loop is the core's (``environment.skill_step.SkillStepper``, as
``ArmEnv``'s), with the env's ``step`` as the plant (``franka.actuation``).

Percept (``percept()``, computed once at the end of ``reset``, after each step and so
within ``joint_reset``; ``observe()`` is its state): by ``FrankaConfig.perception``,
``env`` (default) from the observation the caller's env returned, or ``sim``, the
simulator's state (an oracle); see ``osg_control.franka.perception``. State (10-D, world
frame = the env's frame; the robot base stands at (0, 0, 1.8)): ``[x, y, z, qw, qx, qy,
qz, gripper command, grip force, finger distance]`` of the ``end_effector`` site.

Action (7-D): ``[dx, dy, dz, da, db, dg, g]``, relative TCP position [m] and rotation
vector [rad], clipped to the domain's ``action_bounds`` (``poses.ACTION_BOUNDS``: 4 cm and
0.2 rad per 80 ms step: 0.5 m/s, which keeps a whole kitchen-complete path of about 3 m
within the 280-step limit; the 2 cm of the core's own kitchen is too slow here), and a
gripper command (``g < -0.5`` closes, ``g > 0.5`` opens). The env's arm is the robot
description ``franka-kitchen-panda`` (``robots.franka_kitchen_panda``: the arm compiled from
the env's own MJCF, the joint limits the env enforces, the ``end_effector`` site as TCP),
checked against the env at construction (``franka.arm.check_kitchen_robot``). The core's
differential IK on that description (``control.ik``, the core's rotation convention
``control.rotations``) gives a joint velocity ``v`` for the commanded pose from the perceived
joints (``env``: the observed ones, as the env's own servo target ``observed qpos + 2 a
dt``; ``sim``: the true ones); ``franka.arm.ServoCommand`` turns it into the env's action,
scaled as a whole vector so that ``max |a| <= 1``: when it saturates the TCP moves slower
along the same direction, never along another one. Fingers: ``+1`` opens, ``-1`` closes,
every step.

Truth (``tcp_pose``, ``arm_q``, ``world_state``, ``facts``, ``skill_success``,
``info["world"]``) is for scoring, the skill's reward (Algorithm 1's labels) and the reset's
set-ups and drive (``franka.setup``), never for deciding.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from typing import Any

import gymnasium as gym
import numpy as np

from osg_control.control.rotations import rotation_step
from osg_control.domain.spaces import ACTION_DIM, OBS_DIM, unbounded_observation
from osg_control.domain.spec import Node, SkillSpec
from osg_control.environment.options import check_env_arguments, check_facts_hold
from osg_control.environment.poses import quat_rotation, sample_start_pose
from osg_control.environment.skill_step import SkillStepper
from osg_control.environment.success import GRIPPER_CLOSED_CMD, GRIPPER_OPEN_CMD
from osg_control.errors import DomainError
from osg_control.franka import poses, setup
from osg_control.franka.actuation import KitchenStepActuation
from osg_control.franka.arm import (
    ROBOT,
    FrankaConfig,
    ServoCommand,
    arm_controllers,
    check_kitchen_robot,
)
from osg_control.franka.domain import CONTROL_HZ
from osg_control.franka.perception import (
    ARM,
    PERCEPTIONS,
    REFERENCE_QUAT,
    ROBOT_QVEL,
    FrankaSensors,
)
from osg_control.perception.percept import Percept
from osg_control.robots.registry import get_robot

__all__ = ["REFERENCE_QUAT", "FrankaKitchenAdapter", "check_kitchen"]
RESET_OPTIONS = setup.RESET_OPTIONS


def check_kitchen(env: Any) -> Any:
    """The library's ``KitchenEnv`` under ``env``'s wrappers.

    Raises:
        DomainError: ``env`` is not a FrankaKitchen-v1.
    """
    from gymnasium_robotics.envs.franka_kitchen.kitchen_env import KitchenEnv

    kitchen = getattr(env, "unwrapped", env)
    if not isinstance(kitchen, KitchenEnv):
        raise DomainError(
            f"franka-kitchen wraps a FrankaKitchen-v1 env, got {type(kitchen).__name__}; make "
            f"one with gymnasium.make('FrankaKitchen-v1', tasks_to_complete=[...])"
        )
    return kitchen


class FrankaKitchenAdapter(SkillStepper, gym.Env):
    """A FrankaKitchen-v1 driven by relative TCP commands (see module docstring).

    Args:
        env: the caller's ``gymnasium.make("FrankaKitchen-v1", ...)`` env (any wrapper:
            the ``env`` perception reads the observation its ``reset``/``step`` return).
        nodes: the domain's nodes (a skill's start and end poses).
        world_of: object qpos (21,) and grasp flag -> the world-state vector (the domain's).
        facts_of: world-state vector -> facts.
        skill: the skill whose success the env reports, if any.
        config: IK weights and the perception (default ``env``).
        step_limit: steps after ``reset``'s start (the drive to a random start not
            counted) after which ``step`` reports ``truncated``; None: only the env's own
            limit.
        home: the node a ``position`` reset option draws its orientation from.
        setups: node -> the skills whose scripts bring the env from its reset to that
            node in the world a skill starting there needs (e.g. the microwave opened),
            run by ``reset``: the env's world changes only through its own steps.
        world_facts: the facts ``facts_of`` can give (the ``facts`` reset option may name
            only these; empty: not declared).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": int(CONTROL_HZ)}
    actuation: KitchenStepActuation
    perceptions = PERCEPTIONS
    """The perceptions it supports (``franka.perception``)."""

    def __init__(
        self,
        env: Any,
        nodes: dict[str, Node],
        world_of: Any,
        facts_of: Any,
        skill: SkillSpec | None = None,
        config: FrankaConfig | None = None,
        step_limit: int | None = None,
        home: str = "home",
        setups: Mapping[str, tuple[SkillSpec, ...]] | None = None,
        world_facts: tuple[str, ...] = (),
    ) -> None:
        check_env_arguments(type(self).__name__, skill, config, FrankaConfig)
        self.env = env
        self.world_facts = world_facts
        self.setups = dict(setups or {})
        self.step_limit = step_limit
        self.home = home
        self.kitchen = check_kitchen(env)
        self.model = self.kitchen.model
        self.data = self.kitchen.data
        self.nodes = nodes
        self.skill = skill
        self._facts_of = facts_of
        self.config = config or FrankaConfig()
        self.perception = self.config.perception
        self.render_mode = getattr(env, "render_mode", None)
        self.dt = float(self.kitchen.robot_env.dt)
        self.robot = get_robot(ROBOT)
        """The env's arm (``robots.franka_kitchen_panda``), checked against the env."""
        check_kitchen_robot(self.kitchen, self.robot)
        self.posture = np.asarray(self.kitchen.robot_env.init_qpos[:7], dtype=float).copy()
        self.ik, self.reset_ik = arm_controllers(self.robot, self.config, self.dt, self.posture)
        """The core's IK on the robot: for the steps, and for the joint reset."""
        self.command = ServoCommand(self.robot, self.dt)
        self._arm_dof = np.array([self.model.joint(j).dofadr[0] for j in self.robot.arm.names])
        self.sensors = FrankaSensors(self.kitchen, self.robot, self.ik.tcp_pose, world_of, facts_of)
        self._arm_qpos = self.sensors.arm_qpos
        self._tcp = self.sensors.tcp
        self.observation_space = gym.spaces.Box(*unbounded_observation(), (OBS_DIM,), np.float64)
        self.action_bounds = np.array(poses.ACTION_BOUNDS)
        """The domain's ``action_bounds``: steps clip to them."""
        self.action_space = gym.spaces.Box(
            -self.action_bounds, self.action_bounds, (ACTION_DIM,), np.float64
        )
        self._gripper_cmd = GRIPPER_OPEN_CMD
        self._succeeded = False
        self._steps = 0
        self._episode_over = False
        self.actuation = KitchenStepActuation(env, self.data)
        """The plant: the caller's env, one ``env.step`` per ``step``."""
        self._percept: Percept | None = None
        self.anchor_offsets: dict[str, np.ndarray] = {}
        """Object frames' displacements (``domain.frames``): none, the kitchen's fixtures
        and its nodes do not move."""
        self.script_rng = np.random.default_rng()
        self._noise_rng = np.random.default_rng()

    # ----------------------------------------------------------------- truth
    def finger_forces(self) -> tuple[float, float]:
        """Truth: summed normal contact force [N] on each finger from things not the robot."""
        return self.sensors.finger_forces()

    def true_state(self) -> np.ndarray:
        """Truth: the 10-D state of the simulator (the ``sim`` percept's state)."""
        return self.sensors.true_state(self._gripper_cmd)

    def _true_world(self) -> np.ndarray:
        """Truth: the domain's world-state vector (true object qpos, contact grasp)."""
        return self.sensors.true_world()

    def placement_world(
        self, placements: dict[str, np.ndarray], holding: str | None
    ) -> dict[str, Any]:
        """No ``world`` option: the kitchen's objects are fixtures, none is placed."""
        return {}

    def facts_of(self, world: np.ndarray) -> frozenset[str]:
        """The domain's facts of a world-state vector."""
        return frozenset(self._facts_of(world))

    # ----------------------------------------------------------------- percepts
    def env_observation(self) -> np.ndarray:
        """The env's latest 59-D ``observation`` array, as the caller's env returned it."""
        observation = self.actuation.observation
        if observation is None:
            raise RuntimeError("the env has not been reset")
        return observation.copy()

    def _perceive(self) -> Percept:
        self._percept = self.sensors.perceive(
            self.perception, self.actuation.observation, self._gripper_cmd, self._noise_rng
        )
        return self._percept

    def _controlled(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """What the controller reads: the joints, their TCP pose and the bias torques;
        ``env``: the observed joints and speeds on the arm model, ``sim``: the truth."""
        observation = self.actuation.observation
        if self.perception.name == "sim" or observation is None:
            pos, rot = self.tcp_pose()
            return self.arm_q, pos, rot, self.data.qfrc_bias[self._arm_dof].copy()
        q = observation[ARM].copy()
        pos, rot = self.ik.tcp_pose(q)
        return q, pos, rot, self.command.bias(q, observation[ROBOT_QVEL][:7])

    def _info(
        self, world: np.ndarray | None = None, facts: frozenset[str] | None = None
    ) -> dict[str, Any]:
        """``TruthReadouts._info`` with the env's own task completions."""
        info = super()._info(world, facts)
        info["episode_task_completions"] = self.completed_tasks()
        return info

    # ----------------------------------------------------------------- reset / step
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """The env's own reset (deterministic; ``seed`` sets its observation noise and the
        random start); with a skill whose start node has a set-up (``setups``), that set-up;
        then, with a ``node`` option or a skill, drive to a pose drawn around that node's
        (``radius`` [m] and ``angle`` [rad] per axis, default 0: the node itself;
        ``position`` moves the centre, with the ``home`` node's orientation unless ``node``
        is given) through the env's own steps (they count toward the env's own limit, not
        toward ``steps`` or ``step_limit``). ``max_steps`` bounds the drive (default 40).
        The world is the env's own: ``facts`` and ``gripper``, the core's options, are
        accepted only if they hold (on the truth) in the start it gives.

        Raises:
            EnvOptionError: an unknown option name (the known ones listed), a value out of
                its domain (checked before anything runs), or ``facts``/``gripper`` that do
                not hold at the start.
        """
        start = setup.start_options(self, options)
        super().reset(seed=seed)
        self.script_rng = np.random.default_rng(seed)
        self._noise_rng = np.random.default_rng(None if seed is None else [seed, 1])
        self._percept = None
        self.reset_env(seed)
        self._succeeded = False
        self._steps = 0
        if self.skill is not None and self.skill.start in self.setups:
            setup.set_up(self, self.skill.start, seed)
        if start.node_name is not None:
            position, rotation = sample_start_pose(
                self.np_random,
                start.centre,
                start.radius,
                start.angle,
                quat_rotation(start.node.orientation),
            )
            with self.outside_the_skill():  # the drive is not the skill's episode
                setup.drive_to(self, position, rotation, start.gripper, start.max_steps)
        self._steps = 0
        self._episode_over = False
        world = self.world_state()
        check_facts_hold(start.facts, self.facts_of(world), "the env's own reset")
        self._perceive()
        return self.observe(), self._info(world)

    def reset_env(self, seed: int | None) -> None:
        """The caller's env's own ``reset``, its observation kept, the gripper open."""
        self.actuation.reset(seed)
        self._gripper_cmd = GRIPPER_OPEN_CMD
        self.sensors.forget()

    @contextmanager
    def outside_the_skill(self) -> Iterator[None]:
        """Steps that are not the skill's episode (a set-up, the drive to a start): no
        success check, no reward, no termination from the skill."""
        skill, self.skill = self.skill, None
        try:
            yield
        finally:
            self.skill = skill

    @property
    def steps(self) -> int:
        """Steps taken since the start (the end of ``reset``)."""
        return self._steps

    def completed_tasks(self) -> list[str]:
        """The env's own record of the tasks completed this episode
        (``info["episode_task_completions"]``)."""
        return list(self.actuation.env_info.get("episode_task_completions", []))

    def _command(self, action: np.ndarray) -> np.ndarray:
        """The env's 9-D action for a (clipped) 7-D TCP action at the perceived state."""
        q, pos, rot, bias = self._controlled()
        target = rotation_step(rot, action[3:6])
        velocity = self.ik.solve_velocity(q, pos + action[:3], target)
        return self.arm_action(velocity, bias)

    def arm_action(self, velocity: np.ndarray, bias: np.ndarray) -> np.ndarray:
        """``ServoCommand.action`` with the gripper's command."""
        return self.command.action(velocity, bias, self._gripper_cmd == GRIPPER_CLOSED_CMD)

    def _step_budget(self) -> int | None:
        return self.step_limit

    def _step_percept(self, world: np.ndarray, facts: frozenset[str]) -> Percept:
        return self._perceive()

    # ----------------------------------------------------------------- joint reset
    def joint_reset(self, max_steps: int = 20, tolerance: float = 0.05) -> int:
        """``franka.setup.joint_reset`` on the perceived joints: the steps used (each step
        refreshes the percept).

        Raises:
            SimulationError: the physics diverged.
        """
        return setup.joint_reset(self, max_steps, tolerance)

    def render(self) -> Any:  # type: ignore[override]
        """The wrapped env's frame (its own render mode)."""
        return self.env.render()

    def close(self) -> None:
        self.env.close()
