"""The Panda of Gymnasium-Robotics' FrankaKitchen-v1, compiled from that env's own MJCF, as a
``RobotDescription`` (registered as ``franka-kitchen-panda``).

It is not example-robot-data's Panda (``robots.panda``): the kitchen's MJCF has its own
link frames, a joint 6 of another range, a TCP site ``end_effector`` 0.21 m along link 7,
position servos without gravity compensation, and its env enforces tighter joint bounds.
Everything here is read from the library's files when the description is built
(``kitchen_panda_description``): the joints' limits are what the env enforces, the
intersection of the MJCF joint ranges, the actuators' control ranges and
``franka_config.xml``'s ``pos_bound`` (``enforced_limits``); servo gains, efforts and the
gripper's drive are the MJCF's; the mount is where the kitchen stands the robot. Only the
home posture is the env's code (``KitchenEnv.__init__``'s ``init_qpos``, the reset), copied
into ``RESET_Q``.

Both models come from the same compiled MJCF: the MuJoCo spec is the robot's subtree of the
kitchen model, the Pinocchio arm is built from that spec compiled
(``control.mujoco_pinocchio``), so their kinematics agree (a test holds the TCP pose to 1e-12).
The env's robot is driven through the env's own actuators (the adapter's servo command), not
through ``control.servo``'s drives: the description's ``servo`` gains are the env's position
servos' ``kp`` and the joints' damping, for the record.
"""

from __future__ import annotations

import os
from functools import cache
from typing import Any
from xml.etree import ElementTree

import mujoco
import numpy as np

from osg_control.control import description as rd
from osg_control.control.mujoco_pinocchio import pinocchio_arm_from_mujoco

NAME = "franka-kitchen-panda"
MODEL_FILE = "envs/assets/kitchen_franka/kitchen_assets/kitchen_env_model.xml"
"""The kitchen's MJCF inside the ``gymnasium_robotics`` package."""
CONFIG_FILE = "envs/assets/kitchen_franka/franka_assets/franka_config.xml"
"""The env's robot configuration (its joints' ``pos_bound``)."""
ROBOT_ROOT = "panda0_link0"
ARM_JOINTS = tuple(f"robot:panda0_joint{i}" for i in range(1, 8))
FINGER_JOINTS = ("robot:panda0_finger_joint1", "robot:panda0_finger_joint2")
FINGER_BODIES = ("panda0_leftfinger", "panda0_rightfinger")
TCP_SITE = "end_effector"
"""The MJCF's tool site: the TCP, the MuJoCo site and the Pinocchio frame of that name."""
RESET_Q = (
    1.48388023e-01,
    -1.76848573e00,
    1.84390296e00,
    -2.47685760e00,
    2.60252026e-01,
    7.12533105e-01,
    1.59515394e00,
)
"""The arm at the env's reset (``KitchenEnv.__init__``'s ``init_qpos[:7]``). Its joint 2 lies
5.7 mrad past the MJCF's range (-1.7628): the description's home is this posture held
within the limits; the adapter's IK is drawn to the env's own reset posture."""
CONTROL_HZ = 12.5
"""The env's control rate [Hz]: its robot env steps 40 physics steps of 2 ms per action
(``check_kitchen_robot`` holds a wrapped env to it)."""
ACTION_SPEED = 2.0
"""The joint speed [rad/s] an action of 1 commands (``FrankaRobot.act_rng``): the env's
servo target is ``observed q + ACTION_SPEED * a * dt``, ``a`` in [-1, 1]."""


def _library_file(relative: str) -> str:
    import gymnasium_robotics

    return os.path.join(os.path.dirname(gymnasium_robotics.__file__), relative)


def model_path() -> str:
    """The library's kitchen MJCF."""
    return _library_file(MODEL_FILE)


def config_pos_bound() -> np.ndarray:
    """``franka_config.xml``'s ``pos_bound`` of the arm's joints, (7, 2), as the env reads
    it (``FrankaRobot._read_specs_from_config``)."""
    root = ElementTree.parse(_library_file(CONFIG_FILE)).getroot()
    bounds = [root.find(f"qpos{i}").get("pos_bound").split() for i in range(len(ARM_JOINTS))]  # type: ignore[union-attr]
    return np.array(bounds, dtype=float)


def enforced_limits(model: mujoco.MjModel, pos_bound: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The arm's joint limits as the env enforces them: each joint's MJCF ``range``, its
    position actuator's ``ctrlrange`` and ``pos_bound`` (7, 2), intersected. (7,), (7,)."""
    lower, upper = [], []
    for name, bound in zip(ARM_JOINTS, pos_bound, strict=True):
        joint = model.joint(name)
        act = next(a for a in range(model.nu) if model.actuator_trnid[a, 0] == joint.id)
        bounds = np.array([joint.range, model.actuator_ctrlrange[act], bound])
        lower.append(bounds[:, 0].max())
        upper.append(bounds[:, 1].min())
    return np.array(lower), np.array(upper)


def _robot_subtree() -> mujoco.MjSpec:
    """The robot's bodies of the kitchen MJCF (actuators included, keyframes not) in a spec
    of their own, its base at the origin, every name as the kitchen has it."""
    kitchen = mujoco.MjSpec.from_file(model_path())
    spec = mujoco.MjSpec()
    spec.njmax, spec.nconmax = kitchen.njmax, kitchen.nconmax
    spec.nuser_actuator = kitchen.nuser_actuator
    # Attached under a prefix (MuJoCo warns about an empty one), which is then taken off.
    spec.worldbody.add_frame().attach_body(kitchen.body(ROBOT_ROOT), _PREFIX, "")
    for group in (spec.bodies, spec.joints, spec.sites, spec.actuators, spec.geoms):
        for element in group:
            element.name = element.name.removeprefix(_PREFIX)
    for actuator in spec.actuators:
        actuator.target = actuator.target.removeprefix(_PREFIX)
    for key in list(spec.keys):
        spec.delete(key)
    return spec


_PREFIX = "kitchen/"


def kitchen_arm_spec() -> mujoco.MjSpec:
    """The bare robot (``ModelSource.mujoco``): the kitchen MJCF's robot, fingers included,
    without its actuators and its ``end_effector`` site (the core adds them from the
    description), its arm joints limited to ``enforced_limits``, an equality holding the
    second finger to the first (the env drives both fingers alike), the joints' damping
    moved into the description's drive gains (``servo.kv``, ``gripper.kv``)."""
    spec = _robot_subtree()
    for actuator in list(spec.actuators):
        spec.delete(actuator)
    spec.delete(spec.site(TCP_SITE))
    robot = _facts()
    for name, lo, hi in zip(ARM_JOINTS, robot.lower, robot.upper, strict=True):
        joint = spec.joint(name)
        joint.range = [lo, hi]
        joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
    for name in (*ARM_JOINTS, *FINGER_JOINTS):
        spec.joint(name).damping = [0.0, 0.0, 0.0]  # the description's servo kv holds it
    spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, name1=FINGER_JOINTS[1], name2=FINGER_JOINTS[0])
    return spec


def kitchen_pinocchio_arm() -> Any:
    """The arm-only ``pinocchio.Model`` (``ModelSource.pinocchio``; fingers welded) of
    ``kitchen_arm_spec`` compiled (``control.mujoco_pinocchio``): its limits
    ``enforced_limits``, its speeds ``ACTION_SPEED``, its frame ``end_effector`` the TCP."""
    return pinocchio_arm_from_mujoco(
        kitchen_arm_spec().compile(),
        ARM_JOINTS,
        _tcp(),
        velocity=(ACTION_SPEED,) * len(ARM_JOINTS),
    )


def _tcp() -> rd.TcpFrame:
    """The MJCF's ``end_effector`` site as the TCP, in both models."""
    facts = _facts()
    return rd.TcpFrame(
        body=facts.tcp_body,
        pos=facts.tcp_pos,  # type: ignore[arg-type]
        quat=facts.tcp_quat,  # type: ignore[arg-type]
        frame=TCP_SITE,
        site=TCP_SITE,
    )


@cache
def _compiled_subtree() -> mujoco.MjModel:
    return _robot_subtree().compile()


class _Facts:
    """What the description reads from the compiled MJCF, once."""

    def __init__(self) -> None:
        model = _compiled_subtree()
        self.lower, self.upper = enforced_limits(model, config_pos_bound())
        arm = [model.joint(j) for j in ARM_JOINTS]
        actuators = [
            next(a for a in range(model.nu) if model.actuator_trnid[a, 0] == j.id) for j in arm
        ]
        self.kp = tuple(float(model.actuator_gainprm[a, 0]) for a in actuators)
        self.effort = tuple(float(model.actuator_forcerange[a, 1]) for a in actuators)
        self.damping = tuple(float(model.dof_damping[j.dofadr[0]]) for j in arm)
        self.armature = tuple(float(model.dof_armature[j.dofadr[0]]) for j in arm)
        finger = model.joint(FINGER_JOINTS[0])
        grip = next(a for a in range(model.nu) if model.actuator_trnid[a, 0] == finger.id)
        self.finger_open = float(model.actuator_ctrlrange[grip, 1])
        self.finger_kp = float(model.actuator_gainprm[grip, 0])
        self.finger_force = float(model.actuator_forcerange[grip, 1])
        self.finger_damping = float(model.dof_damping[finger.dofadr[0]])
        self.finger_armature = float(model.dof_armature[finger.dofadr[0]])
        site = model.site(TCP_SITE)
        self.tcp_body = model.body(int(site.bodyid[0])).name
        self.tcp_pos = tuple(float(v) for v in site.pos)
        self.tcp_quat = tuple(float(v) for v in site.quat)
        self.mount = _mount()


@cache
def _facts() -> _Facts:
    return _Facts()


def _mount() -> rd.Placement:
    """Where the kitchen stands the robot: its root body's parent, in the world."""
    kitchen = mujoco.MjSpec.from_file(model_path()).compile()
    data = mujoco.MjData(kitchen)
    mujoco.mj_kinematics(kitchen, data)
    parent = int(kitchen.body_parentid[kitchen.body(ROBOT_ROOT).id])
    position = tuple(float(v) for v in data.xpos[parent])
    quat = tuple(float(v) for v in data.xquat[parent])
    return position, quat  # type: ignore[return-value]


def kitchen_panda_description() -> rd.RobotDescription:
    """The FrankaKitchen-v1 Panda (module docstring)."""
    facts = _facts()
    n = len(ARM_JOINTS)
    return rd.RobotDescription(
        name=NAME,
        summary="Franka Panda of Gymnasium-Robotics' FrankaKitchen-v1 (its MJCF), 7 joints",
        model=rd.ModelSource(mujoco=kitchen_arm_spec, pinocchio=kitchen_pinocchio_arm),
        arm=rd.ArmJoints(
            names=ARM_JOINTS,
            lower=tuple(float(v) for v in facts.lower),
            upper=tuple(float(v) for v in facts.upper),
            velocity=(ACTION_SPEED,) * n,
            effort=facts.effort,
            armature=facts.armature,
        ),
        servo=rd.ServoGains(kp=facts.kp, kv=facts.damping),
        tcp=_tcp(),
        gripper=rd.Gripper(
            joints=FINGER_JOINTS,
            bodies=FINGER_BODIES,
            open_position=facts.finger_open,
            kp=facts.finger_kp,
            kv=facts.finger_damping,  # the finger joints' damping, as the actuator's
            force=facts.finger_force,
            armature=facts.finger_armature,
        ),
        home_q=tuple(float(v) for v in np.clip(RESET_Q, facts.lower, facts.upper)),
        control_hz=CONTROL_HZ,
        # The env's observation: joint encoders and finger joints, no force sensor.
        sensors=("encoders", "finger_width"),
        gravity_compensation=False,
        mount=facts.mount,
    )
