"""The Franka Panda from example-robot-data's ``panda.urdf``, for MuJoCo and Pinocchio alike.

Both simulators load the *same* URDF file, so the kinematics agree by construction (a test
checks TCP pose and Jacobian to 1e-9). MuJoCo gets speed-capped joint drives
(``control.servo``), gravity compensation, a TCP site and a home keyframe added through
``mujoco.MjSpec``; Pinocchio gets an arm-only model (fingers locked) whose
``panda_hand_tcp`` frame is the TCP.
"""

from __future__ import annotations

import os
import re
import site
import sys
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import mujoco
import numpy as np

from osg_control.control.mujoco_log import install_warning_handler
from osg_control.control.servo import add_speed_capped_drives
from osg_control.errors import ModelNotFoundError

install_warning_handler()

ARM_JOINTS: tuple[str, ...] = tuple(f"panda_joint{i}" for i in range(1, 8))
FINGER_JOINTS: tuple[str, ...] = ("panda_finger_joint1", "panda_finger_joint2")
TCP_FRAME = "panda_hand_tcp"
TCP_SITE = "tcp"
HOME_Q = np.array([0.0, -0.785398, 0.0, -2.35619, 0.0, 1.5707, 0.785398])
"""Home arm configuration [rad] (the SRDF's ``default`` group state)."""
FINGER_OPEN = 0.04
"""Finger joint travel when open [m] (each finger; distance between fingers is twice this)."""
SHOULDER_HEIGHT = 0.333
"""Height [m] of the shoulder (joint 2) above the arm's base."""
REACH = 0.855
"""The Panda's reach [m] from its shoulder: no TCP target farther away can be reached."""
CONTROL_HZ = 20.0
"""The rate of the arm's control loop [Hz]: one IK solve and servo target per 50 ms."""


def substeps_per_control_step(timestep: float) -> int:
    """Physics substeps of ``timestep`` [s] in one control step (``CONTROL_HZ``)."""
    return round(1.0 / (CONTROL_HZ * timestep))


HOME_KEY = "arm-home"
"""The MuJoCo keyframe of ``HOME_Q`` (fingers open) in every model built here."""

# The TCP in the frame of panda_link7: link7 -> link8 (+0.107 z) -> hand (yaw -pi/4) -> tcp
# (+0.1034 z), all read from the URDF's fixed joints. MuJoCo fuses those static links into
# panda_link7, so the site is attached there.
_TCP_IN_LINK7_POS = (0.0, 0.0, 0.107 + 0.1034)
_TCP_IN_LINK7_QUAT = (np.cos(-np.pi / 8), 0.0, 0.0, np.sin(-np.pi / 8))

# Position-servo gains per arm joint [N m / rad] and damping [N m s / rad]: kv/kp of about
# 15 ms, so a 50 ms control step is tracked to within a few per cent.
_ARM_KP = (4500.0, 4500.0, 3500.0, 3500.0, 2000.0, 2000.0, 2000.0)
_ARM_KV = (70.0, 70.0, 50.0, 50.0, 30.0, 30.0, 30.0)
_ARM_FORCE_LIMIT = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
_GRIPPER_KP = 2000.0
_GRIPPER_KV = 100.0
_GRIPPER_FORCE_LIMIT = 70.0
"""The Panda hand's continuous grip force [N]."""


@dataclass(frozen=True)
class PandaFiles:
    """Paths of the example-robot-data Panda description."""

    urdf: Path
    mesh_dir: Path
    package_root: Path


def _candidate_roots() -> list[Path]:
    roots: list[Path] = []
    env_root = os.environ.get("EXAMPLE_ROBOT_DATA_DIR")
    if env_root:
        roots.append(Path(env_root))
    prefixes = [*site.getsitepackages(), site.getusersitepackages(), *sys.path]
    for prefix in prefixes:
        roots.append(Path(prefix) / "cmeel.prefix" / "share" / "example-robot-data")
    roots.append(Path(sys.prefix) / "share" / "example-robot-data")
    return roots


@cache
def find_panda() -> PandaFiles:
    """Locate ``panda.urdf`` in the installed example-robot-data package.

    Raises:
        ModelNotFoundError: if no candidate directory holds the URDF; lists every path tried.
    """
    tried = []
    for root in _candidate_roots():
        urdf = root / "robots" / "panda_description" / "urdf" / "panda.urdf"
        tried.append(str(urdf))
        if urdf.is_file():
            return PandaFiles(urdf, urdf.parent.parent / "meshes", root.parent)
    raise ModelNotFoundError(
        "example-robot-data's panda.urdf not found (pip install example-robot-data, or set "
        "EXAMPLE_ROBOT_DATA_DIR). Searched:\n  " + "\n  ".join(tried)
    )


def _urdf_for_mujoco(files: PandaFiles) -> str:
    """Resolve ``package://`` paths; MuJoCo cannot read the ``.dae`` visuals, use the STLs."""
    text = files.urdf.read_text()
    prefix = "package://example-robot-data/robots/panda_description/meshes/"
    collision = str(files.mesh_dir / "collision")
    text = re.sub(re.escape(prefix) + r"visual/(\w+)\.dae", collision + r"/\1.stl", text)
    text = text.replace(prefix, str(files.mesh_dir) + "/")
    if "package://" in text:
        raise ModelNotFoundError(f"unresolved package:// path left in {files.urdf}")
    compiler = '<mujoco><compiler discardvisual="false" balanceinertia="true"/></mujoco>'
    return re.sub(r"(<robot[^>]*>)", r"\1" + compiler, text, count=1)


def panda_spec(with_fingers: bool = True) -> mujoco.MjSpec:
    """Build the Panda's MuJoCo spec from the URDF, with actuators, TCP site and home key.

    Args:
        with_fingers: keep the two finger joints and the gripper actuator. The arm-only
            model (``False``) is what the mink IK backend works on.
    """
    spec = mujoco.MjSpec.from_string(_urdf_for_mujoco(find_panda()))
    spec.modelname = "panda"
    link7 = spec.body("panda_link7")
    link7.add_site(name=TCP_SITE, pos=_TCP_IN_LINK7_POS, quat=_TCP_IN_LINK7_QUAT, size=[0.005] * 3)
    for body in spec.bodies:
        if body.name.startswith("panda_"):
            body.gravcomp = 1.0
    if not with_fingers:
        for name in ("panda_leftfinger", "panda_rightfinger"):
            spec.delete(spec.body(name))
        for equality in list(spec.equalities):
            spec.delete(equality)
    for name in ARM_JOINTS:
        spec.joint(name).armature = 0.1
    add_speed_capped_drives(
        spec, ARM_JOINTS, _ARM_KP, _ARM_KV, _ARM_FORCE_LIMIT, urdf_velocity_limits()
    )
    qpos_home = list(HOME_Q)
    if with_fingers:
        gripper = spec.add_actuator(
            name="gripper", target=FINGER_JOINTS[0], trntype=mujoco.mjtTrn.mjTRN_JOINT
        )
        gripper.set_to_position(kp=_GRIPPER_KP, kv=_GRIPPER_KV)
        gripper.ctrlrange = [0.0, FINGER_OPEN]
        gripper.ctrllimited = True
        gripper.forcerange = [-_GRIPPER_FORCE_LIMIT, _GRIPPER_FORCE_LIMIT]
        gripper.forcelimited = True
        for name in FINGER_JOINTS:
            # Reflected inertia and damping of the hand's drive: without them the 15 g
            # fingers reach metres per second and tunnel through thin parts.
            spec.joint(name).armature = 0.1
            spec.joint(name).damping = [20.0, 0.0, 0.0]
        qpos_home += [FINGER_OPEN, FINGER_OPEN]
    # The stiffness actuators' targets, the damping actuators' zero velocities, the gripper.
    ctrl_home = list(HOME_Q) + [0.0] * len(ARM_JOINTS) + ([FINGER_OPEN] if with_fingers else [])
    spec.add_key(name=HOME_KEY, qpos=qpos_home, ctrl=ctrl_home)
    return spec


def load_pinocchio_arm():  # type: ignore[no-untyped-def]
    """Build the arm-only Pinocchio model (fingers locked open) from the same URDF.

    Returns:
        The ``pinocchio.Model``; its frame ``panda_hand_tcp`` is the TCP.
    """
    import pinocchio as pin

    full = pin.buildModelFromUrdf(str(find_panda().urdf))
    locked = [full.getJointId(name) for name in FINGER_JOINTS]
    q_ref = pin.neutral(full)
    return pin.buildReducedModel(full, locked, q_ref)


@cache
def _velocity_limits() -> tuple[float, ...]:
    return tuple(float(v) for v in load_pinocchio_arm().velocityLimit)


def urdf_velocity_limits() -> np.ndarray:
    """Per-joint velocity limits [rad/s] read from the URDF (via Pinocchio's parser)."""
    return np.array(_velocity_limits())
