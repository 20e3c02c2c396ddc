"""What the FrankaKitchen-v1 adapter perceives: ``env`` (the env's own observation) or
``sim`` (the simulator's state, an oracle).

``env`` (the domain's default) reads only the observation that the caller's env object
returns from ``reset`` and ``step`` (through any wrapper of theirs), its ``observation``
array (59-D, ``kitchen_env.py``): robot joint positions [0:9] (7 arm joints, 2 fingers)
and velocities [9:18] with the env's uniform noise (``robot_noise_ratio`` 0.01 times
``franka_config.xml``'s amplitude 0.1: +-1 mrad, +-1 mm per finger), object qpos [18:39]
and velocities [39:59] with ``object_noise_ratio`` (0.0005 times 0.005-0.1); plus the
robot's known kinematics and actuators:

- TCP: forward kinematics of the observed arm joints on the robot description's arm model
  (``franka-kitchen-panda``, compiled from the env's own MJCF; the core IK's ``tcp_pose``),
  optionally with the paper's Gaussian TCP noise
  (``PerceptionSpec.tcp_noise``); the quaternion in the hemisphere of ``REFERENCE_QUAT``.
- Finger width: the sum of the two observed finger joints.
- Grasp (the world's ``grasped``): the gripper commanded closed and the fingers at least
  ``GRASP_WIDTH`` apart, having stopped there (``GRASP_SPEED``) since the close: closed on
  something. Once detected it holds while the fingers stay closed that wide (a handle
  pulled along its arc moves the fingers in their joints, 2-4 cm/s, without letting go).
- Grip force: the observation has no force sensor. With a grasp detected, the finger
  servos' own effort on the thing held, ``kp * (observed finger - target)`` of the
  weaker finger (the env's finger target is 0 when closing: the finger servos' gain
  ``gripper.kp`` of the description times its
  observed position; in steady state equal to the contact force, since nothing else
  loads a finger); 0 otherwise (empty or open hand). The shipped policies were trained
  on the contact force: on the microwave's handle it reads 6-10 N here against 8-13 N;
  during a knob sweep 0 against up to 60 N (the bar pressing the closed fingers). What
  this difference costs on the benchmark is measured in docs/results.md.
- Objects: the observed object qpos (not ``achieved_goal``, the simulator's noise-free
  state); facts by the library's completion rule on them (the domain's ``facts_of``).

``sim`` is the privileged readout (true ``end_effector`` site, true object qpos, the
fingers' contact forces): an oracle, for comparison only.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.environment.sensing import tcp_state
from osg_control.environment.success import GRIPPER_CLOSED_CMD
from osg_control.errors import DomainError
from osg_control.perception.percept import Percept
from osg_control.perception.spec import PerceptionSpec

PERCEPTIONS: tuple[str, ...] = ("env", "sim")
"""The perceptions this domain supports; the first is its default."""
OBSERVATION_SIZE = 59
ARM = slice(0, 7)
FINGERS = slice(7, 9)
ROBOT_QVEL = slice(9, 18)
FINGER_QVEL = slice(16, 18)
OBJECT_QPOS = slice(18, 39)
OBJECT_QVEL = slice(39, 59)
"""The layout of the env's ``observation`` array (``KitchenEnv._get_obs``)."""
REFERENCE_QUAT = (0.5, -0.5, -0.5, -0.5)
"""The hemisphere of the state's quaternion: tool z along +y, fingers along x (about the
orientation at the env's reset)."""
GRASP_FORCE = 1.0
"""Truth (``sim``, scoring): both fingers pressing harder than this [N] count as a grasp."""
GRASP_WIDTH = 0.01
"""``env``: closed fingers (the sum of the two finger joints) stopped at least this far
apart [m] hold something: empty, they close to 0 +- 2 mm of observation noise; on the
microwave's handle they stop 4.2-4.5 cm apart, on the hinge cabinet's 4.5-4.6 cm."""
GRASP_SPEED = 0.02
"""``env``: the fingers count as stopped below this observed speed [m/s]. The finger
servos are critically damped (kp 500 N/m, damping 100 N s/m, armature 5 kg: 10 rad/s), so
an empty hand closing at this speed has its fingers within 2 mm of closed, well under
``GRASP_WIDTH`` with the observation's +-2 mm."""


def observation_vector(observation: Any) -> np.ndarray:
    """The env's 59-D ``observation`` array from what its ``reset``/``step`` returned (the
    library's dict, or the array itself from a wrapper that unpacks it).

    Raises:
        DomainError: neither a dict with a 59-D ``observation`` nor a 59-D array.
    """
    vector = observation.get("observation") if isinstance(observation, dict) else observation
    try:
        array = np.array(vector, dtype=float)
    except (TypeError, ValueError):
        array = np.zeros(0)
    if array.shape != (OBSERVATION_SIZE,):
        raise DomainError(
            "franka-kitchen perception 'env' reads the env's 59-D observation (the dict's "
            f"'observation' or a 59-D array), got {type(observation).__name__} of shape "
            f"{getattr(array, 'shape', None)}"
        )
    return array


def contact_grasp(finger_forces: tuple[float, float]) -> bool:
    """Truth: both fingers squeeze something (contact normal forces over ``GRASP_FORCE``)."""
    return bool(min(finger_forces) > GRASP_FORCE)


def width_grasp(
    gripper_cmd: float, fingers: np.ndarray, finger_speeds: np.ndarray, held: bool = False
) -> bool:
    """Percept: the gripper commanded closed, the fingers at least ``GRASP_WIDTH`` apart
    and stopped there (``GRASP_SPEED``), or ``held`` (a grasp detected at the previous
    percept) (see module docstring)."""
    closed_on_something = (
        gripper_cmd == GRIPPER_CLOSED_CMD and float(np.sum(fingers)) >= GRASP_WIDTH
    )
    stopped = float(np.abs(finger_speeds).max()) < GRASP_SPEED
    return bool(closed_on_something and (held or stopped))


def servo_effort(fingers: np.ndarray, grasped: bool, kp: float) -> float:
    """Percept: the weaker finger's servo effort [N] on a grasped thing (the closing
    target is 0; ``kp`` the finger servos' gain [N/m]), 0 without a grasp (see module
    docstring)."""
    return float(max(0.0, kp * float(np.min(fingers)))) if grasped else 0.0


def robot_bodies(model: mujoco.MjModel, robot: RobotDescription) -> set[int]:
    """The ids of the robot's bodies in ``model``: the subtree of its first arm joint's
    parent body (its base), the fingers included."""
    base = int(model.body_parentid[model.jnt_bodyid[model.joint(robot.arm.names[0]).id]])
    bodies = {base}
    for body in range(base + 1, model.nbody):
        if int(model.body_parentid[body]) in bodies:
            bodies.add(body)
    return bodies


class FrankaSensors:
    """The adapter's readouts of one FrankaKitchen-v1: the simulator's truth (scoring,
    set-ups, the ``sim`` perception) and the percepts of a named perception.

    Args:
        kitchen: the library's unwrapped ``KitchenEnv``.
        robot: its arm's description (joints, fingers, TCP site, finger servo gain).
        fk: arm joints -> TCP position and rotation matrix (the arm model's kinematics).
        world_of: object qpos (21,) and a grasp flag -> the domain's world vector.
        facts_of: world vector -> facts.
    """

    def __init__(
        self,
        kitchen: Any,
        robot: RobotDescription,
        fk: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
        world_of: Callable[[np.ndarray, bool], np.ndarray],
        facts_of: Callable[[np.ndarray], frozenset[str]],
    ) -> None:
        model = self.model = kitchen.model
        self.data = kitchen.data
        self.fk = fk
        self._world_of = world_of
        self._facts_of = facts_of
        self.arm_qpos = np.array([model.joint(j).qposadr[0] for j in robot.arm.names])
        self.finger_qpos = np.array([model.joint(j).qposadr[0] for j in robot.gripper.joints])
        self.finger_kp = robot.gripper.kp
        self.tcp = model.site(robot.tcp.site).id
        self.finger_bodies = [model.body(b).id for b in robot.gripper.bodies]
        self.robot_bodies = robot_bodies(model, robot)
        self._held = False

    # ---------------------------------------------------------------- truth
    def true_tcp(self) -> tuple[np.ndarray, np.ndarray]:
        """The ``end_effector`` site's true position [m] and rotation matrix."""
        tcp = self.tcp
        return self.data.site_xpos[tcp].copy(), self.data.site_xmat[tcp].reshape(3, 3).copy()

    def finger_forces(self) -> tuple[float, float]:
        """Truth: summed normal contact force [N] on each finger from things not the robot."""
        totals = [0.0, 0.0]
        wrench = np.zeros(6)
        fingers, robot = self.finger_bodies, self.robot_bodies
        for i in range(self.data.ncon):
            contact = self.data.contact[i]
            bodies = (
                int(self.model.geom_bodyid[contact.geom1]),
                int(self.model.geom_bodyid[contact.geom2]),
            )
            for f, finger in enumerate(fingers):
                if finger in bodies:
                    other = bodies[1] if bodies[0] == finger else bodies[0]
                    if other not in robot:
                        mujoco.mj_contactForce(self.model, self.data, i, wrench)
                        totals[f] += abs(float(wrench[0]))
        return totals[0], totals[1]

    def true_state(self, gripper_cmd: float) -> np.ndarray:
        """Truth: the 10-D state of the true site, grip force the weaker finger's contact
        force, finger width the true finger joints' sum."""
        pos, rot = self.true_tcp()
        fingers = float(self.data.qpos[self.finger_qpos].sum())
        force = float(min(self.finger_forces()))
        return tcp_state(pos, rot, gripper_cmd, force, fingers, REFERENCE_QUAT)

    def true_world(self) -> np.ndarray:
        """Truth: the world vector of the true object qpos and the contact grasp."""
        grasped = contact_grasp(self.finger_forces())
        return np.asarray(self._world_of(self.data.qpos[9:].copy(), grasped), dtype=float)

    # ---------------------------------------------------------------- percepts
    def forget(self) -> None:
        """A new episode (the env's reset): no grasp carried over."""
        self._held = False

    def perceive(
        self,
        spec: PerceptionSpec,
        observation: np.ndarray | None,
        gripper_cmd: float,
        rng: np.random.Generator,
    ) -> Percept:
        """The percept of ``spec`` (``env``: from ``observation``, the env's latest 59-D
        array; ``sim``: the simulator), TCP noise ``spec.tcp_noise`` added to the state."""
        if spec.name == "sim":
            world = self.true_world()
            state = self.true_state(gripper_cmd)
            joints = self.data.qpos[self.arm_qpos].copy()
        else:
            if observation is None:
                raise RuntimeError("the env has not been reset")
            state, joints, world = self.env_readout(observation, gripper_cmd)
        if spec.tcp_noise > 0:
            state[:3] += rng.normal(0.0, spec.tcp_noise, 3)
        return Percept(state, joints, world, frozenset(self._facts_of(world)))

    def env_readout(
        self, observation: np.ndarray, gripper_cmd: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``env``: the state, arm joints and world from the observation alone (and the
        grasp detected at the previous percept; see the module docstring)."""
        joints = observation[ARM].copy()
        fingers = observation[FINGERS]
        pos, rot = self.fk(joints)
        grasped = width_grasp(gripper_cmd, fingers, observation[FINGER_QVEL], self._held)
        self._held = grasped
        effort = servo_effort(fingers, grasped, self.finger_kp)
        state = tcp_state(pos, rot, gripper_cmd, effort, float(fingers.sum()), REFERENCE_QUAT)
        world = np.asarray(self._world_of(observation[OBJECT_QPOS].copy(), grasped), dtype=float)
        return state, joints, world
