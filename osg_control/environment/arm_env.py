"""``ArmEnv``: a robot arm in a domain's scene as a Gymnasium env with the paper's state and action.

Observation (10-D, robot base frame): ``[x, y, z, qw, qx, qy, qz, gripper command,
grip force, finger distance]`` — TCP position [m], TCP orientation (``w, x, y, z``, sign
chosen in the hemisphere of ``TOP_DOWN_QUAT`` so it is continuous over the task space),
the latched gripper command (+1 open, -1 closed), the gripper actuator's force magnitude
[N] and the distance between the fingers [m].

Action (7-D): ``[dx, dy, dz, da, db, dg, g]`` — a relative TCP command (position [m],
rotation vector [rad], base frame), each clipped to ``action_bounds``, and a gripper
command: ``g < -0.5`` closes, ``g > 0.5`` opens, otherwise the gripper holds.

The arm is a ``RobotDescription`` (``control.description``): its joints, limits, drives,
TCP, gripper and control rate (e.g. 20 Hz: 25 physics steps of 2 ms).
A differential-IK QP
(``osg_control.control.ik``) turns each command into joint position targets within joint and
velocity limits; the position servos chase them within the velocity limits on every
physics substep (``osg_control.control.servo``). With a ``skill``, the env gives the skill's
sparse reward (1 on the step its success predicate first holds, which also terminates the
episode).

A domain's env subclasses ``ArmEnv`` and supplies the scene: the compiled model, the
world-state readout (a float vector of named fields), the facts it abstracts to, and how a
start world is put in place (objects, what the hand holds). Nothing here knows any skill
catalogue or scene object.
"""

from __future__ import annotations

from functools import partial
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.control.ik import DiffIKController
from osg_control.control.robot_model import GRIPPER_ACTUATOR
from osg_control.control.servo import uncap_drive
from osg_control.domain.frames import offsets_of
from osg_control.domain.spaces import (
    ACTION_DIM,
    OBS_DIM,
    PAPER_ACTION_BOUNDS,
    observation_bounds,
)
from osg_control.domain.spec import Node, SkillSpec
from osg_control.environment.camera_sensing import CameraSensing
from osg_control.environment.config import RESET_OPTIONS, EnvConfig, as_slice
from osg_control.environment.joint_reset import JointReset
from osg_control.environment.options import (
    GRIPPER_STATES,
    check_env_arguments,
    check_facts_hold,
    check_names,
    check_start_options,
    choice_option,
    facts_option,
    node_option,
    reset_options,
)
from osg_control.environment.perceiving import Perceiving
from osg_control.environment.poses import quat_rotation, sample_start_pose
from osg_control.environment.sensing import ArmSensors
from osg_control.environment.start_placement import StartPlacement
from osg_control.environment.stepping import ArmControlStep, MujocoActuation
from osg_control.environment.success import GRIPPER_CLOSED_CMD, GRIPPER_OPEN_CMD, success_holds
from osg_control.errors import EnvOptionError, SimulationError
from osg_control.perception.percept import Percept
from osg_control.perception.sensors import sensor_slices

__all__ = [
    "GRIPPER_CLOSED_CMD",
    "GRIPPER_OPEN_CMD",
    "ArmEnv",
    "EnvConfig",
    "success_holds",
]


class ArmEnv(Perceiving, StartPlacement, gym.Env):
    """A robot arm driven by relative TCP commands in a domain's scene (see module docstring).

    Subclasses implement the scene's hooks (``scene_hooks.SceneHooks``): ``build_model``,
    ``read_world``, ``facts_of``; they may override ``check_world``, ``place_world``,
    ``snap_start``, ``held_geoms`` and ``finger_opening``, and declare ``world_facts``,
    ``world_options``, ``holdable``, ``objects`` and ``world_sensors``. Its step loop
    (``skill_step``, the plant ``stepping.MujocoActuation``), percepts (``perceiving``),
    truth readouts (``truth``) and start placement (``start_placement``) are the bases'
    and parts' jobs.

    Args:
        nodes: the domain's nodes (start poses and skills' termination poses).
        home: the node a reset starts at without a skill or ``node`` option.
        skill: the skill whose reward and termination the env gives, if any.
        config: noise, step budget, IK and random-start options.
        render_mode: ``"rgb_array"`` for ``render``.
        robot: the arm (``control.description``; a domain's env gives its default).
        action_bounds: the per-step bound of each action component (its domain's
            ``action_bounds``; default the paper's).
    """

    metadata = {"render_modes": ["rgb_array"]}
    actuation: MujocoActuation
    camera = "overview"
    """The model camera ``render`` uses."""

    def __init__(
        self,
        nodes: dict[str, Node],
        home: str,
        skill: SkillSpec | None = None,
        config: EnvConfig | None = None,
        render_mode: str | None = None,
        *,
        robot: RobotDescription,
        action_bounds: tuple[float, ...] = PAPER_ACTION_BOUNDS,
    ) -> None:
        check_env_arguments(type(self).__name__, skill, config, EnvConfig)
        self.config = config or EnvConfig()
        self.robot = robot
        self.metadata = {**self.metadata, "render_fps": int(robot.control_hz)}
        if self.config.perception.name not in self.perceptions:
            raise EnvOptionError(
                f"EnvConfig.perception: {type(self).__name__} simulates the perceptions "
                f"{', '.join(self.perceptions)}, not {self.config.perception.name!r}"
            )
        self.nodes = nodes
        self.home = home
        self.skill = skill
        self.render_mode = render_mode
        self.model = self.build_model()
        self.data = mujoco.MjData(self.model)
        self.ik = DiffIKController(robot, self.config.ik)
        self._joint_reset = JointReset(robot, self.config.ik)
        self.n_substeps = robot.substeps(self.model.opt.timestep)
        joints = robot.arm.names
        self._arm_qpos = as_slice([self.model.joint(j).qposadr[0] for j in joints])
        self._arm_dof = as_slice([self.model.joint(j).dofadr[0] for j in joints])
        self._arm_act = as_slice([self.model.actuator(j).id for j in joints])
        if not self.config.limit_joint_speed:
            uncap_drive(self.model, joints)
        gripper = robot.gripper
        self._finger_open = gripper.open_position
        self._gripper_act = self.model.actuator(GRIPPER_ACTUATOR).id
        self.actuation = MujocoActuation(
            ArmControlStep(
                self.model,
                self.data,
                robot,
                self._arm_qpos,
                self._arm_dof,
                self._arm_act,
                self.n_substeps,
                self.config.limit_joint_speed,
            ),
            self._gripper_act,
            self._finger_open,
        )
        """The plant: the scene's physics, one control step per ``step``."""
        self._finger_qpos = np.array([self.model.joint(j).qposadr[0] for j in gripper.joints])
        self._tcp = self.model.site(robot.tcp.site).id
        base = self.model.body_rootid[self.model.jnt_bodyid[self.model.joint(joints[0]).id]]
        self._robot_bodies = {
            b for b in range(self.model.nbody) if self.model.body_rootid[b] == base
        }
        """The robot's bodies: those under its base (attached to the scene's world)."""
        self.observation_space = gym.spaces.Box(*observation_bounds(robot), (OBS_DIM,), np.float64)
        self.action_bounds = np.array(action_bounds, dtype=float)
        """The per-step bound of each action component; steps clip to them."""
        self.action_space = gym.spaces.Box(
            -self.action_bounds, self.action_bounds, (ACTION_DIM,), np.float64
        )
        self._gripper_cmd = GRIPPER_OPEN_CMD
        self._steps = 0
        self._succeeded = False
        self._episode_over = False
        self._renderer: mujoco.Renderer | None = None
        self._sensor_slices = sensor_slices(self.world_sensors)
        self.sensors = ArmSensors(
            self.model,
            self._arm_qpos,
            self._finger_qpos,
            self._gripper_act,
            self._tcp,
            gripper.width_scale,
            "grip_force" in robot.sensors,
        )
        """The arm's simulated encoders, gripper and TCP readouts."""
        self._percept: Percept | None = None
        self.cameras: CameraSensing | None = None
        """The ``camera`` perception's cameras (made at the first percept)."""
        self.anchor_offsets: dict[str, np.ndarray] = {}
        """Each object's true displacement from its nominal place at the last reset (the
        frame the env's own skill is scored in; scoring and scripted collection only)."""

    # ----------------------------------------------------------------- reset
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset to a start state.

        Args:
            seed: seeds the env's generator (start-state sampling and observation noise).
            options: ``node`` (a node name; default: the skill's start node, else the
                home node), ``position`` (TCP centre [m], overrides the node's), ``radius``
                [m] and ``angle`` [rad] of the random start (defaults: the config's),
                ``gripper`` (``"open"``/``"closed"``), ``facts`` (start world facts;
                default: the skill's ``start_facts``), ``world`` (the scene's own explicit
                options, see the domain's env), ``holding`` (an object name or ``None``;
                default: the skill's ``holding``).

        Raises:
            EnvOptionError: an unknown option name or ``world`` entry (the known ones
                listed), a value out of its domain, or options that contradict each other
                (``facts`` that do not hold in the start world the other options give, an
                open ``gripper`` while ``holding``); nothing is simulated.
            SimulationError: no collision-free start, or the physics diverged placing it.
        """
        options = reset_options(options)
        check_names(options, RESET_OPTIONS, "reset option")
        node = self.nodes[
            node_option(options, self.skill.start if self.skill else self.home, self.nodes)
        ]
        gripper = choice_option("gripper", options.get("gripper", node.gripper), GRIPPER_STATES)
        holding = options.get("holding", self.skill.holding if self.skill else None)
        choice_option("holding", holding, (None, *self.holdable))
        if holding is not None and options.get("gripper") == "open":
            raise EnvOptionError(
                f"reset options contradict each other: gripper 'open' while holding {holding!r}"
            )
        world = options.get("world", {})
        if not isinstance(world, dict):
            raise EnvOptionError(f"reset option world must be a dict, got {world!r}")
        check_names(world, self.world_options, "world reset option")
        self.check_world(world, holding)
        default_centre = np.asarray(node.position, dtype=float)
        if node.anchor is not None:  # the node moves with the object the world places
            default_centre = default_centre + self.placement_offsets(world).get(
                node.anchor, np.zeros(3)
            )
        centre, radius, angle = check_start_options(
            options.get("position", default_centre),
            options.get("radius", self.config.start_radius),
            options.get("angle", self.config.start_angle),
        )
        asked = options.get("facts")
        default_facts = self.skill.start_facts if self.skill else frozenset()
        facts = default_facts if asked is None else facts_option(asked, self.world_facts)
        super().reset(seed=seed)  # after the checks: a refused reset changes nothing
        self.seed_fixture_noise(fresh=seed is not None)
        orientation = quat_rotation(node.orientation)
        for _attempt in range(50):
            pos, rot = sample_start_pose(self.np_random, centre, radius, angle, orientation)
            pos, rot = self.snap_start(pos, rot, holding, world, facts)
            if self._place(pos, rot, gripper, holding, world, facts):
                break
        else:
            raise SimulationError(
                f"no collision-free start found within {radius} m of {centre.tolist()}"
            )
        if asked is not None:
            given = {k: options[k] for k in ("world", "holding", "gripper") if k in options}
            check_facts_hold(facts, self.facts_of(self.read_world()), f"the options {given}")
        self._steps = 0
        self._succeeded = False
        self._episode_over = False
        self.actuation.peak = 0.0
        if self.cameras is not None:
            self.cameras.reset()
        world = self.read_world()
        self.anchor_offsets = offsets_of(self.objects, tuple(self.world_sensors), world)
        self._perceive(world)
        return self.observe(), self._info(world)

    # ----------------------------------------------------------------- step
    @property
    def peak_joint_speed_ratio(self) -> float:
        """Peak |arm joint velocity| / its limit over every simulated substep since the last
        reset (steps and joint resets; the start's settling is not commanded motion)."""
        return self.actuation.peak

    def _command(self, action: np.ndarray) -> np.ndarray:
        """The IK's joint targets from the encoders (the perceived joints)."""
        return self.ik.relative_step(self.percept().joints, action[:6])

    def _step_budget(self) -> int | None:
        return self.skill.max_steps if self.skill else self.config.max_steps

    def _step_percept(self, world: np.ndarray, facts: frozenset[str]) -> Percept:
        return self._perceive(world, facts, decision=False)

    def _sensor_info(self) -> dict[str, Any]:
        if self.cameras is None:
            return {}
        return {"camera": self.cameras.report(float(self.data.time))}

    def _simulate(self, arm_target: np.ndarray) -> str | None:
        """Run one control step of physics toward ``arm_target`` (``MujocoActuation``);
        return a failure reason if the simulation diverged."""
        return self.actuation.simulate(arm_target)[0]

    # ----------------------------------------------------------------- joint reset
    def joint_reset(self, max_steps: int = 40, tolerance: float = 0.05) -> int:
        """Drive the joints toward the home posture (``IKConfig.posture``) while the TCP
        holds its pose (``joint_reset.JointReset``: null-space motion from the encoders,
        with the perception's encoder noise; an arm without a null space takes no step).

        Returns:
            The number of control steps used.

        Raises:
            SimulationError: the physics diverged (or the joint state is non-finite).
        """
        encoders = partial(self.sensors.encoders, self.data, self.config.perception, self.np_random)
        try:
            return self._joint_reset.run(
                self.data, encoders, self.ik.posture, self._simulate, max_steps, tolerance
            )
        finally:
            self._perceive()

    # ----------------------------------------------------------------- render
    def render(self) -> np.ndarray | None:  # type: ignore[override]
        """An RGB frame from the ``overview`` camera (needs an OpenGL context, e.g. EGL)."""
        if self.render_mode != "rgb_array":
            return None
        if self._renderer is None:
            self._renderer = mujoco.Renderer(self.model, height=480, width=640)
        self._renderer.update_scene(self.data, camera=self.camera)
        return np.asarray(self._renderer.render())

    def close(self) -> None:
        if self.cameras is not None:
            self.cameras.close()
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
