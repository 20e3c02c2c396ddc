"""A ``RobotDescription``'s models: the driven MuJoCo arm and the Pinocchio arm.

MuJoCo gets the robot's bare spec (``ModelSource.mujoco``) with what the description
declares added: the TCP site, gravity compensation, the joints' armature, the speed-capped
joint drives (``control.servo``), the gripper's position actuator and a home keyframe.
Pinocchio gets the arm-only model of ``ModelSource.pinocchio``, whose ``TcpFrame.frame`` is
the TCP. ``check_models`` holds both against the description (joints, limits, TCP, gripper).
Helpers for robots described by a URDF (``urdf_for_mujoco``, ``reduced_urdf_model``,
``find_example_robot_data``) live here too.
"""

from __future__ import annotations

import os
import re
import site
import sys
from functools import cache
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from osg_control.control.description import (
    ORIGIN,
    Placement,
    RobotDescription,
    RobotDescriptionError,
)
from osg_control.control.mujoco_log import install_warning_handler
from osg_control.control.servo import add_speed_capped_drives
from osg_control.errors import ModelNotFoundError

install_warning_handler()

HOME_KEY = "arm-home"
"""The MuJoCo keyframe of the robot's home posture (fingers open) in every model built here."""
GRIPPER_ACTUATOR = "gripper"
"""The gripper's position actuator in every model built here."""
_SLIDE_OR_HINGE = (mujoco.mjtJoint.mjJNT_SLIDE, mujoco.mjtJoint.mjJNT_HINGE)


def robot_spec(robot: RobotDescription, with_gripper: bool = True) -> mujoco.MjSpec:
    """The robot's MuJoCo spec with its TCP site, drives, gripper actuator and home key.

    Args:
        robot: the description.
        with_gripper: keep the gripper's bodies and actuator. The arm-only model
            (``False``) is what the mink IK backend works on.
    """
    spec = robot.model.mujoco()
    spec.modelname = robot.name
    _place_base(spec, robot.mount)
    tcp = robot.tcp
    spec.body(tcp.body).add_site(name=tcp.site, pos=tcp.pos, quat=tcp.quat, size=[0.005] * 3)
    if robot.gravity_compensation:
        for body in spec.bodies:
            if body.name != spec.worldbody.name:
                body.gravcomp = 1.0
    gripper = robot.gripper
    if not with_gripper:
        for name in gripper.bodies:
            spec.delete(spec.body(name))
        for equality in list(spec.equalities):
            spec.delete(equality)
    for name, armature in zip(robot.arm.names, robot.arm.armature, strict=True):
        spec.joint(name).armature = armature
    add_speed_capped_drives(
        spec,
        robot.arm.names,
        robot.servo.kp,
        robot.servo.kv,
        robot.arm.effort,
        np.array(robot.arm.velocity),
    )
    home = list(robot.home_q)
    if with_gripper:
        actuator = spec.add_actuator(
            name=GRIPPER_ACTUATOR, target=gripper.joints[0], trntype=mujoco.mjtTrn.mjTRN_JOINT
        )
        actuator.set_to_position(kp=gripper.kp, kv=gripper.kv)
        actuator.ctrlrange = [0.0, gripper.open_position]
        actuator.ctrllimited = True
        actuator.forcerange = [-gripper.force, gripper.force]
        actuator.forcelimited = True
        for name in gripper.joints:
            spec.joint(name).armature = gripper.armature
            spec.joint(name).damping = [gripper.damping, 0.0, 0.0]
        home += [gripper.open_position] * len(gripper.joints)
    # The stiffness actuators' targets, the damping actuators' zero velocities, the gripper.
    ctrl = list(robot.home_q) + [0.0] * robot.n_joints
    ctrl += [gripper.open_position] if with_gripper else []
    spec.add_key(name=HOME_KEY, qpos=home, ctrl=ctrl)
    return spec


def _place_base(spec: mujoco.MjSpec, mount: Placement) -> None:
    """Move the bodies hanging from the world (the robot's base) to ``mount``."""
    if mount == ORIGIN:
        return
    position, quat = np.array(mount[0], dtype=float), np.array(mount[1], dtype=float)
    for body in spec.worldbody.bodies:
        placed_pos, placed_quat = np.zeros(3), np.zeros(4)
        mujoco.mju_mulPose(
            placed_pos, placed_quat, position, quat, np.array(body.pos), np.array(body.quat)
        )
        body.pos, body.quat = placed_pos, placed_quat


def pinocchio_arm(robot: RobotDescription) -> Any:
    """The robot's arm-only ``pinocchio.Model`` (``ModelSource.pinocchio``) with its base at
    ``robot.mount``: the joints and frames hanging from the universe moved there."""
    model = robot.model.pinocchio()
    if robot.mount == ORIGIN:
        return model
    import pinocchio as pin

    position, quat = robot.mount
    w, x, y, z = quat
    placement = pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), np.array(position))
    for joint in range(1, model.njoints):
        if model.parents[joint] == 0:
            model.jointPlacements[joint] = placement * model.jointPlacements[joint]
    for frame in list(model.frames)[1:]:  # the universe stays the world
        if frame.parentJoint == 0:
            frame.placement = placement * frame.placement
    return model


@cache
def arm_model(robot: RobotDescription) -> mujoco.MjModel:
    """The compiled arm-only model (gripper removed), shared read-only: the IK's and
    ``check_models``' (copy it before changing it)."""
    return robot_spec(robot, with_gripper=False).compile()


@cache
def workspace(robot: RobotDescription) -> tuple[tuple[float, float, float], float]:
    """A sphere every TCP position of ``robot`` lies in, in scene coordinates: centred on
    its first joint's anchor (at its mount), of radius the sum of the distances between
    consecutive joint anchors and from the last to the TCP at the home posture (each a
    rigid link, so by the triangle inequality no posture reaches farther).

    Returns:
        The centre [m] and the radius [m].
    """
    model = arm_model(robot)
    data = mujoco.MjData(model)
    data.qpos[:] = robot.home_q
    mujoco.mj_kinematics(model, data)
    anchors = np.array([data.xanchor[model.joint(name).id] for name in robot.arm.names])
    points = np.vstack([anchors, data.site(robot.tcp.site).xpos])
    radius = float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())
    x, y, z = (float(v) for v in anchors[0])
    return (x, y, z), radius


def check_models(robot: RobotDescription) -> None:
    """Hold the robot's models against its description.

    Raises:
        RobotDescriptionError: naming the robot and what does not match: an arm joint or
            gripper joint missing or not a hinge/slide, a joint limit that differs from the
            model's, the TCP body or frame missing, a gripper whose open position is
            outside its driven joint's range.
        ModelNotFoundError: a model file the builders need is missing.
    """
    name = robot.name
    spec = robot.model.mujoco()
    joints = {j.name: j for j in spec.joints}
    for joint in (*robot.arm.names, *robot.gripper.joints):
        if joint not in joints or joints[joint].type not in _SLIDE_OR_HINGE:
            raise RobotDescriptionError(
                f"robot {name!r}: joint {joint!r} is not a hinge or slide joint of its MuJoCo "
                f"model (joints: {sorted(joints)})"
            )
    if spec.body(robot.tcp.body) is None:
        raise RobotDescriptionError(f"robot {name!r}: TCP body {robot.tcp.body!r} not in the model")
    bodies = {b.name for b in spec.bodies}
    missing = [b for b in robot.gripper.bodies if b not in bodies]
    if missing:
        raise RobotDescriptionError(f"robot {name!r}: gripper bodies {missing} not in the model")
    driven = spec.compile().joint(robot.gripper.joints[0])
    if driven.limited[0] and not driven.range[0] <= robot.gripper.open_position <= driven.range[1]:
        raise RobotDescriptionError(
            f"robot {name!r}: the gripper cannot be driven open: open_position "
            f"{robot.gripper.open_position} is outside joint {driven.name!r}'s range "
            f"{driven.range.tolist()}"
        )
    model = arm_model(robot)
    if model.nq != robot.n_joints:
        raise RobotDescriptionError(
            f"robot {name!r}: its arm-only MuJoCo model has {model.nq} joints, the description "
            f"{robot.n_joints} (is a gripper joint missing from gripper.joints?)"
        )
    lower, upper = np.array(robot.arm.lower), np.array(robot.arm.upper)
    ranges = np.array([model.joint(j).range for j in robot.arm.names])
    _same(name, "MuJoCo position limits", ranges, np.stack([lower, upper], axis=1))
    pin_model = robot.model.pinocchio()
    if tuple(pin_model.names[1:]) != robot.arm.names:
        raise RobotDescriptionError(
            f"robot {name!r}: its Pinocchio arm's joints {list(pin_model.names[1:])} are not "
            f"arm.names {list(robot.arm.names)}"
        )
    if not pin_model.existFrame(robot.tcp.frame):
        raise RobotDescriptionError(
            f"robot {name!r}: TCP frame {robot.tcp.frame!r} not in its Pinocchio model"
        )
    _same(name, "Pinocchio lower limits", pin_model.lowerPositionLimit, lower)
    _same(name, "Pinocchio upper limits", pin_model.upperPositionLimit, upper)
    _same(name, "Pinocchio velocity limits", pin_model.velocityLimit, np.array(robot.arm.velocity))


def _same(robot: str, what: str, model: Any, described: np.ndarray) -> None:
    if not np.allclose(np.asarray(model, dtype=float), described, rtol=0.0, atol=1e-9):
        raise RobotDescriptionError(
            f"robot {robot!r}: {what} {np.asarray(model).tolist()} differ from its "
            f"description's {described.tolist()}"
        )


def reduced_urdf_model(urdf: Path, locked_joints: tuple[str, ...]) -> Any:
    """The ``pinocchio.Model`` of ``urdf`` with ``locked_joints`` fixed at their neutral
    positions (e.g. a gripper's), for ``ModelSource.pinocchio``."""
    import pinocchio as pin

    full = pin.buildModelFromUrdf(str(urdf))
    locked = [full.getJointId(name) for name in locked_joints]
    return pin.buildReducedModel(full, locked, pin.neutral(full))


def urdf_for_mujoco(
    urdf: Path, package_prefix: str, mesh_dir: Path, *, drop_visuals: bool = False
) -> str:
    """A URDF's text for MuJoCo: ``package_prefix`` (a ``package://`` path) resolved to
    ``mesh_dir``, the ``.dae`` visuals (which MuJoCo cannot read) replaced by the collision
    STLs (or with ``drop_visuals`` every visual removed: what is seen is what collides),
    visuals kept and inertias balanced.

    Raises:
        ModelNotFoundError: a ``package://`` path is left unresolved.
    """
    text = urdf.read_text()
    if drop_visuals:
        text = re.sub(r"<visual>.*?</visual>", "", text, flags=re.DOTALL)
    collision = str(mesh_dir / "collision")
    text = re.sub(re.escape(package_prefix) + r"visual/(\w+)\.dae", collision + r"/\1.stl", text)
    text = text.replace(package_prefix, str(mesh_dir) + "/")
    if "package://" in text:
        raise ModelNotFoundError(f"unresolved package:// path left in {urdf}")
    compiler = '<mujoco><compiler discardvisual="false" balanceinertia="true"/></mujoco>'
    return re.sub(r"(<robot[^>]*>)", r"\1" + compiler, text, count=1)


def _example_robot_data_roots() -> list[Path]:
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
def find_example_robot_data(relative: str) -> Path:
    """A file of the installed example-robot-data package, e.g.
    ``robots/<name>_description/urdf/<name>.urdf``.

    Raises:
        ModelNotFoundError: no candidate directory holds it; lists every path tried.
    """
    tried = []
    for root in _example_robot_data_roots():
        path = root / relative
        tried.append(str(path))
        if path.is_file():
            return path
    raise ModelNotFoundError(
        f"example-robot-data's {relative} not found (pip install example-robot-data, or set "
        "EXAMPLE_ROBOT_DATA_DIR). Searched:\n  " + "\n  ".join(tried)
    )
