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
from osg_control.control.divergence import DivergenceWatch, non_finite_state
from osg_control.control.ik import (
    DiffIKController,
    solve_ik,
)
from osg_control.control.robot_model import GRIPPER_ACTUATOR, HOME_KEY
from osg_control.control.servo import uncap_drive
from osg_control.domain.frames import offsets_of
from osg_control.domain.spaces import (
    ACTION_DIM,
    OBS_DIM,
    PAPER_ACTION_BOUNDS,
    observation_bounds,
)
from osg_control.domain.spec import Node, SkillSpec
from osg_control.environment.actions import checked_action
from osg_control.environment.camera_sensing import CameraPerception, CameraSensing
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
from osg_control.environment.poses import quat_rotation, sample_start_pose
from osg_control.environment.scene_hooks import SceneHooks
from osg_control.environment.sensing import ArmSensors
from osg_control.environment.stepping import ArmControlStep
from osg_control.environment.success import GRIPPER_CLOSED_CMD, GRIPPER_OPEN_CMD, success_holds
from osg_control.errors import EnvOptionError, SimulationError
from osg_control.perception.percept import Percept
from osg_control.perception.sensors import noisy_world, sensor_slices
from osg_control.perception.spec import SIMULATED_PERCEPTIONS

__all__ = [
    "GRIPPER_CLOSED_CMD",
    "GRIPPER_OPEN_CMD",
    "ArmEnv",
    "EnvConfig",
    "success_holds",
]


class ArmEnv(SceneHooks, gym.Env):
    """A robot arm driven by relative TCP commands in a domain's scene (see module docstring).

    Subclasses implement the scene's hooks (``scene_hooks.SceneHooks``): ``build_model``,
    ``read_world``, ``facts_of``; they may override ``check_world``, ``place_world``,
    ``snap_start``, ``held_geoms`` and ``finger_opening``, and declare ``world_facts``,
    ``world_options``, ``holdable``, ``objects`` and ``world_sensors``.

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
    camera = "overview"
    """The model camera ``render`` uses."""
    camera_perception: CameraPerception | None = None
    """The scene's fixed cameras and what they locate (the ``camera`` perception), if any."""

    @property
    def perceptions(self) -> tuple[str, ...]:
        """The perceptions it simulates: ``camera`` too where the scene declares cameras."""
        return SIMULATED_PERCEPTIONS + (("camera",) if self.camera_perception is not None else ())

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
        self._control_step = ArmControlStep(
            self.model,
            self.data,
            robot,
            self._arm_qpos,
            self._arm_dof,
            self._arm_act,
            self.n_substeps,
            self.config.limit_joint_speed,
        )
        self._step_speed_ratio = 0.0
        self.peak_joint_speed_ratio = 0.0
        """Peak |arm joint velocity| / its limit over every simulated substep since the last
        reset (steps and joint resets; the start's settling is not commanded motion)."""
        gripper = robot.gripper
        self._finger_qpos = np.array([self.model.joint(j).qposadr[0] for j in gripper.joints])
        self._finger_open = gripper.open_position
        self._gripper_act = self.model.actuator(GRIPPER_ACTUATOR).id
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

    # ----------------------------------------------------------------- state
    @property
    def episode_over(self) -> bool:
        """Whether a step since the last reset came back terminated or truncated: the
        episode is over and, by Gymnasium's protocol, takes no more steps."""
        return self._episode_over

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

    def true_state(self) -> np.ndarray:
        """Truth (scoring): the 10-D state of the simulator (the ``sim`` percept's state)."""
        return self.sensors.true_state(self.data, self._gripper_cmd)

    def world_state(self) -> np.ndarray:
        """The scene's true state beyond the robot: for scoring and labels, never for
        deciding (``percept().world`` is what the robot perceives)."""
        return self.read_world()

    def facts(self) -> frozenset[str]:
        """The world facts that hold now in the simulator (scoring; ``percept().facts`` is
        what the robot believes)."""
        return self.facts_of(self.read_world())

    def observe(self) -> np.ndarray:
        """The perceived 10-D state of the latest percept (a copy)."""
        return self.percept().state.copy()

    def percept(self) -> Percept:
        """What the robot perceived at the last reset, step or joint reset: the only input
        of whatever decides (the executor, policies, classifier, fact detectors)."""
        if self._percept is None:
            raise RuntimeError("the env has not been reset")
        return self._percept

    def sense(self) -> Percept:
        """Read the sensors now without stepping (e.g. after the scene was edited from
        outside); ``percept`` then returns this reading."""
        return self._perceive()

    def _perceive(
        self,
        truth: np.ndarray | None = None,
        truth_facts: frozenset[str] | None = None,
        decision: bool = True,
    ) -> Percept:
        """Read the simulated sensors once (``config.perception``) and keep the percept
        (``truth``: the world vector, if the caller has read it already; ``truth_facts``:
        its facts, if computed, which an exact ``sim`` perception then reuses; ``decision``:
        a decision point, where the ``camera`` perception renders whatever its rate)."""
        spec = self.config.perception
        truth = self.read_world() if truth is None else truth
        if truth.shape != (len(self.world_sensors),):
            raise EnvOptionError(
                f"{type(self).__name__}: world_sensors name {len(self.world_sensors)} fields, "
                f"read_world gives {truth.shape}; declare a sensor for every world field"
            )
        if spec.name == "sim":
            state = self.sensors.true_state(self.data, self._gripper_cmd)
            facts = self.facts_of(truth) if truth_facts is None else truth_facts
            self._percept = Percept(state, self.arm_q, truth, facts)
        else:
            state, joints = self.sensors.perceived(
                self.data, self._gripper_cmd, spec, self.np_random
            )
            seen = noisy_world(spec, self.np_random, truth, self._sensor_slices)
            if spec.name == "camera":
                seen = self._camera_world(state, seen, decision)
            world = self.detect_world(state, seen)
            self._percept = Percept(state, joints, world, self.facts_of(world))
        return self._percept

    def _camera_world(self, state: np.ndarray, world: np.ndarray, decision: bool) -> np.ndarray:
        """``world`` with the objects the scene's cameras locate (``camera_sensing``; the
        ``camera`` perception is refused at construction where the scene declares none)."""
        if self.cameras is None:
            assert self.camera_perception is not None  # ``perceptions`` lists camera
            self.cameras = CameraSensing(
                self.model,
                self.camera_perception,
                self.config.perception,
                self.world_sensors,
                self.robot.control_hz,
            )
        previous = self._percept.facts if self._percept is not None else frozenset()
        held = {frame.name for frame in self.objects if frame.held_fact in previous}
        return self.cameras.read(self.data, state[:3], world, held, decision)

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
        self.peak_joint_speed_ratio = 0.0
        if self.cameras is not None:
            self.cameras.reset()
        world = self.read_world()
        self.anchor_offsets = offsets_of(self.objects, tuple(self.world_sensors), world)
        self._perceive(world)
        return self.observe(), self._info(world)

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

    # ----------------------------------------------------------------- step
    def check_action(self, action: np.ndarray) -> np.ndarray:
        """Validate an action (shape (7,), finite) and clip it to ``action_bounds``.

        Raises:
            ValueError: wrong shape or NaN/inf; nothing reaches the actuators.
        """
        return checked_action(action, self.action_bounds)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Apply one 50 ms control step (see module docstring).

        A non-finite joint position (set from outside since the last step) ends the
        episode as a divergence: ``terminated``, ``info["failure"]`` naming the joint,
        nothing simulated and nothing sent to the actuators (a non-finite velocity MuJoCo
        reports itself, as ``BADQVEL``).

        Raises:
            ValueError: a malformed action (``check_action``).
        """
        action = self.check_action(action)
        failure = non_finite_state(self.data, ("qpos",))  # MuJoCo answers a bad qvel itself
        if failure is None:
            if action[6] < -0.5:
                self._gripper_cmd = GRIPPER_CLOSED_CMD
            elif action[6] > 0.5:
                self._gripper_cmd = GRIPPER_OPEN_CMD
            # The controller reads the encoders: the perceived joints.
            q_target = self.ik.relative_step(self.percept().joints, action[:6])
            self.data.ctrl[self._gripper_act] = (
                self._finger_open if self._gripper_cmd == GRIPPER_OPEN_CMD else 0.0
            )
            failure = self._simulate(q_target)
        else:
            self._step_speed_ratio = 0.0  # nothing simulated
        self._steps += 1
        world = self.read_world()
        facts = self.facts_of(world)
        reward = 0.0
        terminated = False
        if failure is None and self.skill is not None and not self._succeeded:
            if self._truth_success(self.skill, facts):
                self._succeeded = True
                reward = 1.0
                terminated = True
        if failure is not None:
            terminated = True
        budget = self.skill.max_steps if self.skill else self.config.max_steps
        truncated = not terminated and budget is not None and self._steps >= budget
        self._episode_over = self._episode_over or terminated or truncated
        info = self._info(world, facts)
        info["percept"] = self._perceive(world, facts, decision=False)
        if self.cameras is not None:
            info["camera"] = self.cameras.report(float(self.data.time))
        info["action_applied"] = action
        info["joint_speed_ratio"] = self._step_speed_ratio
        if failure is not None:
            info["failure"] = failure
        return self.observe(), reward, terminated, truncated, info

    def _simulate(self, arm_target: np.ndarray) -> str | None:
        """Run one control step of physics toward ``arm_target`` (``stepping.ArmControlStep``)
        and record its peak joint speed; return a failure reason if the simulation diverged."""
        failure, peak = self._control_step.run(arm_target)
        self._record_peak(peak)
        return failure

    def _record_peak(self, peak: float) -> None:
        self.peak_joint_speed_ratio = max(self.peak_joint_speed_ratio, peak)
        self._step_speed_ratio = peak

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
        facts = self.facts_of(self.read_world() if world is None else world)
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
        world = self.read_world() if world is None else world
        return {
            "world": world,
            "world_facts": sorted(self.facts_of(world) if facts is None else facts),
            "steps": self._steps,
            "success": self._succeeded,
            "arm_q": self.arm_q,
        }

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
