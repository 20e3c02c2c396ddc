"""The UR5 from example-robot-data's ``ur5_robot.urdf`` with a parallel-jaw gripper, for MuJoCo
and Pinocchio alike.

Both models load the *same* URDF, so the arm's kinematics agree by construction (a test checks
TCP pose and Jacobian to 1e-9); the TCP is placed in both from one figure, ``TCP_DEPTH`` along
the URDF's ``tool0`` frame. MuJoCo cannot read the URDF's ``.dae`` visuals: they are dropped
and the URDF's collision STLs (convex hulls in MuJoCo) are what is seen and what collides.
example-robot-data's UR5 has no gripper, so ``ur5_bare_spec`` mounts one on the flange, modelled
on a Robotiq 2F-85: two prismatic fingers driven together (an equality couples them, as a
mimic joint would), ``MAX_OPENING`` between the pads, friction pads with torsional friction.
The real 2F-85's linkage (its fingertips swing on an arc) is not modelled. The SRDF's disabled
collision pairs are excluded; Pinocchio gets the arm (six joints) with the TCP frame
``TCP_FRAME``. These are the builders of ``robots.ur5``'s description: the core
(``control.robot_model``) adds the TCP site, drives, gripper actuator, home key and mount.

Tool convention (the Panda's): the TCP's z axis points out of the flange (the approach
direction) and the fingers close along its y axis; the TCP lies between the pads' centres.
"""

from __future__ import annotations

from functools import cache
from xml.etree import ElementTree

import mujoco
import numpy as np

from osg_control.control.robot_model import find_example_robot_data, urdf_for_mujoco

URDF_PATH = "robots/ur_description/urdf/ur5_robot.urdf"
"""The URDF inside example-robot-data (its ``ur5`` robot)."""
SRDF_PATH = "robots/ur_description/srdf/ur5.srdf"
"""The SRDF listing the link pairs that never collide."""
ARM_JOINTS: tuple[str, ...] = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
FINGER_JOINTS: tuple[str, ...] = ("left_finger_joint", "right_finger_joint")
"""The gripper's two slide joints; each one's value is its pad's distance from the TCP [m]."""
FINGER_BODIES: tuple[str, ...] = ("left_finger", "right_finger")
FLANGE_FRAME = "tool0"
"""The URDF's flange frame (z out of the flange), where the gripper is mounted."""
TCP_BODY = "wrist_3_link"
"""The link that carries the flange and the TCP site (MuJoCo fuses ``tool0`` into it)."""
_MARKER_LINK = "ee_link"
"""The URDF's end-effector marker link, whose 1 cm collision box is dropped."""
TCP_FRAME = "ur5_tcp"
"""The TCP frame added to the Pinocchio model."""

FINGER_OPEN = 0.0425
"""Each finger's travel when open [m]: ``MAX_OPENING`` between the pads."""
MAX_OPENING = 2 * FINGER_OPEN
"""The gripper's stroke [m], the Robotiq 2F-85's 85 mm."""
GRIP_FORCE = 100.0
"""The gripper actuator's force limit [N] (the 2F-85 grips with 20-235 N)."""
TCP_DEPTH = 0.134
"""The TCP's distance from the flange along its z axis [m]: the pads' centre."""

HOME_Q = np.array([-0.9241, -1.9798, 1.4823, -1.0733, -1.5708, -2.4949])
"""Home arm configuration [rad]: elbow up, the TCP pointing down above the base's +x side
(mounted where the kitchen puts it, ``kitchen.scene.ROBOT_MOUNTS``, it is at the kitchen's
home node, 0.35 0 0.45)."""

# Gripper geometry in the flange frame (z out of the flange, fingers closing along y) [m].
# A 75 mm coupling disc, a palm box, and per finger a link box reaching from the palm to the
# fingertip (TCP_DEPTH + pad half height) with a friction pad on its inner face; 0.9 kg in
# all, as the 2F-85 and its coupling.
_COUPLING_SIZE = (0.0375, 0.0075, 0.0)  # radius, half length
_COUPLING_MASS = 0.15
_PALM_HALF = (0.03, 0.055, 0.03)
_PALM_CENTRE_Z = 0.045
_PALM_MASS = 0.65
_PALM_BOTTOM = _PALM_CENTRE_Z + _PALM_HALF[2]
_PAD_HALF = (0.011, 0.002, 0.011)
_PAD_FRICTION = (1.5, 0.02, 0.001)
_PAD_MASS = 0.005
_FINGER_HALF = (0.011, 0.006, (TCP_DEPTH + _PAD_HALF[2] - _PALM_BOTTOM) / 2)
_FINGER_MASS = 0.045

SERVO_KP = (6000.0, 6000.0, 4500.0, 2000.0, 2000.0, 2000.0)
"""Position-servo stiffness per arm joint [N m/rad] (``control.servo``'s drive)."""
SERVO_KV = (90.0, 90.0, 70.0, 30.0, 30.0, 30.0)
"""Servo damping per arm joint [N m s/rad]: kv/kp of about 15 ms, as the Panda's, so a 50 ms
control step is tracked to within a few per cent."""
ARM_ARMATURE = (0.1,) * 6
"""Reflected rotor inertia per arm joint [kg m^2]."""
GRIPPER_KP = 2000.0
"""The gripper actuator's position gain [N/m]."""
GRIPPER_KV = 100.0
"""The gripper actuator's damping [N s/m]."""
FINGER_ARMATURE = 0.1
"""Each finger joint's reflected inertia [kg] ..."""
FINGER_DAMPING = 20.0
"""... and damping [N s/m]: light fingers otherwise reach metres per second and tunnel
through thin parts."""


@cache
def _urdf_arm():  # type: ignore[no-untyped-def]
    import pinocchio as pin

    return pin.buildModelFromUrdf(str(find_example_robot_data(URDF_PATH)))


def tcp_in_flange() -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """The TCP site's position [m] and orientation (w, x, y, z) in ``TCP_BODY``."""
    position, rotation = flange_to_tcp()
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rotation.flatten())
    x, y, z = (float(v) for v in position)
    w, qx, qy, qz = (float(v) for v in quat)
    return (x, y, z), (w, qx, qy, qz)


def flange_to_tcp() -> tuple[np.ndarray, np.ndarray]:
    """The TCP's position [m] and rotation matrix in the flange link's (``TCP_BODY``)
    frame: the URDF's ``tool0`` placement, then ``TCP_DEPTH`` along its z axis."""
    model = _urdf_arm()
    tool0 = model.frames[model.getFrameId(FLANGE_FRAME)].placement
    rotation = np.array(tool0.rotation)
    return np.array(tool0.translation) + rotation[:, 2] * TCP_DEPTH, rotation


def load_pinocchio_arm():  # type: ignore[no-untyped-def]
    """The arm's Pinocchio model (six joints, no gripper) with the TCP frame ``TCP_FRAME``,
    its base link at the model's origin (``robot_model.pinocchio_arm`` mounts it).

    Returns:
        A new ``pinocchio.Model`` (callers may modify it).
    """
    import pinocchio as pin

    model = pin.Model(_urdf_arm())
    flange = model.getFrameId(FLANGE_FRAME)
    position, rotation = flange_to_tcp()
    frame = model.frames[flange]
    model.addFrame(
        pin.Frame(
            TCP_FRAME,
            frame.parentJoint,
            flange,
            pin.SE3(rotation, position),
            pin.FrameType.OP_FRAME,
        )
    )
    return model


def joint_limits() -> tuple[np.ndarray, np.ndarray]:
    """The arm joints' lower and upper position limits [rad] from the URDF."""
    model = _urdf_arm()
    return np.array(model.lowerPositionLimit), np.array(model.upperPositionLimit)


def velocity_limits() -> np.ndarray:
    """The arm joints' velocity limits [rad/s] from the URDF."""
    return np.array(_urdf_arm().velocityLimit)


def effort_limits() -> np.ndarray:
    """The arm joints' effort limits [N m] from the URDF."""
    return np.array(_urdf_arm().effortLimit)


def _urdf_for_mujoco() -> str:
    """The URDF's text for MuJoCo without its ``.dae`` visuals (``robot_model.urdf_for_mujoco``)."""
    urdf = find_example_robot_data(URDF_PATH)
    root = urdf.parents[len(URDF_PATH.split("/")) - 1]
    return urdf_for_mujoco(urdf, "package://example-robot-data/", root, drop_visuals=True)


def disabled_collision_pairs() -> list[tuple[str, str]]:
    """The SRDF's link pairs that are never checked for collision."""
    root = ElementTree.parse(find_example_robot_data(SRDF_PATH)).getroot()
    return [(e.attrib["link1"], e.attrib["link2"]) for e in root.iter("disable_collisions")]


def _add_gripper(flange: mujoco.MjsBody, position: np.ndarray, quat: np.ndarray) -> None:
    """Mount the gripper (``FINGER_JOINTS``, ``FINGER_BODIES``) on ``flange`` at the
    ``tool0`` pose ``position``, ``quat``."""
    mount = flange.add_body(name="gripper_base", pos=position, quat=quat)
    mount.add_geom(
        name="gripper_coupling",
        type=mujoco.mjtGeom.mjGEOM_CYLINDER,
        size=list(_COUPLING_SIZE),
        pos=[0.0, 0.0, _COUPLING_SIZE[1]],
        mass=_COUPLING_MASS,
    )
    mount.add_geom(
        name="gripper_palm",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=list(_PALM_HALF),
        pos=[0.0, 0.0, _PALM_CENTRE_Z],
        mass=_PALM_MASS,
    )
    finger_half = _FINGER_HALF
    pad_half = _PAD_HALF
    pad_z = TCP_DEPTH - _PALM_BOTTOM
    for name, joint, side in zip(FINGER_BODIES, FINGER_JOINTS, (1.0, -1.0), strict=True):
        # At the joint's value q the finger's inner face (its origin) is q from the TCP.
        finger = mount.add_body(name=name, pos=[0.0, 0.0, _PALM_BOTTOM])
        slide = finger.add_joint(
            name=joint, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0.0, side, 0.0]
        )
        slide.range = [0.0, FINGER_OPEN]
        slide.limited = True
        inner = 2 * pad_half[1]
        finger.add_geom(
            name=f"{name}_link",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=list(finger_half),
            pos=[0.0, side * (inner + finger_half[1]), finger_half[2]],
            mass=_FINGER_MASS,
        )
        finger.add_geom(
            name=f"{name}_pad",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=list(pad_half),
            pos=[0.0, side * pad_half[1], pad_z],
            friction=list(_PAD_FRICTION),
            condim=4,
            mass=_PAD_MASS,
        )


def ur5_bare_spec() -> mujoco.MjSpec:
    """The bare UR5 from the URDF with the gripper mounted: links (collision meshes), joints,
    inertias, the SRDF's excluded pairs, the fingers' slide joints and their coupling; no
    actuator, TCP site or keyframe (``robot_model.robot_spec`` adds them); the base link at
    the origin (``robot_model.robot_spec`` mounts it).
    """
    spec = mujoco.MjSpec.from_string(_urdf_for_mujoco())
    spec.modelname = "ur5"
    for geom in list(spec.body(_MARKER_LINK).geoms):
        spec.delete(geom)  # a 1 cm box where the gripper's coupling is
    for link1, link2 in disabled_collision_pairs():
        spec.add_exclude(bodyname1=link1, bodyname2=link2)
    tool0 = _urdf_arm().frames[_urdf_arm().getFrameId(FLANGE_FRAME)].placement
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.array(tool0.rotation).flatten())
    _add_gripper(spec.body(TCP_BODY), np.array(tool0.translation), quat)
    coupling = spec.add_equality(
        type=mujoco.mjtEq.mjEQ_JOINT, name1=FINGER_JOINTS[1], name2=FINGER_JOINTS[0]
    )
    polynomial = np.zeros_like(coupling.data)
    polynomial[1] = 1.0  # right = 0 + 1 * left: the two fingers move together
    coupling.data = polynomial
    coupling.solref = [0.005, 1.0]  # stiffer than the default 0.02 s: the fingers centre
    return spec
