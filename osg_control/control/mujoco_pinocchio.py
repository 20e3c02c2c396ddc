"""A robot's arm-only Pinocchio model built from its compiled MuJoCo model.

For a robot whose model is an MJCF (``ModelSource.mujoco``), ``pinocchio_arm_from_mujoco``
builds the ``ModelSource.pinocchio`` side from the same compiled ``mujoco.MjModel``: every
body with its compiled pose and inertia, a joint per arm joint, every other joint welded at
its reference position (a gripper's fingers), and the TCP as a frame. MuJoCo's compiler is
the reference (it resolves ``euler``/``axisangle``, ``compiler angle``, defaults, included
files), so both models hold the same numbers and their kinematics agree to rounding
(``tests/test_mujoco_pinocchio.py``: TCP pose and Jacobian to 1e-12).

Why not ``pinocchio.buildModelFromMJCF``: it parses MJCF text again, and a spec cut out of
a larger model (a robot's subtree of a scene) exists as text only through
``MjSpec.to_xml()``, which writes every number to 6 significant digits: an
``euler="1.57 0 1.57"`` compiles to the quaternion (0.500398..., 0.49999984..., ...) and is
written back as ``0.500398 0.5 -0.499602 0.5``; on a 7-joint arm that put the TCP 1.4e-6
off MuJoCo's. The compiled model has no such loss, and needs no mesh files or include paths
resolved a second time.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np

from osg_control.control.description import RobotDescriptionError, TcpFrame

_UNBOUNDED = np.finfo(float).max
"""Pinocchio's parsers' value for a limit the model does not declare."""


def pinocchio_arm_from_mujoco(
    model: mujoco.MjModel,
    joints: Sequence[str],
    tcp: TcpFrame,
    velocity: Sequence[float] | None = None,
) -> Any:
    """The arm-only ``pinocchio.Model`` of a compiled MuJoCo model.

    Args:
        model: the robot's compiled MuJoCo model (its base hanging from the world).
        joints: the arm's hinge or slide joints, base to tip: the model's joints, in this
            order. Every other joint is welded at its reference position.
        tcp: the TCP, added as the frame ``tcp.frame`` at ``tcp.pos``/``tcp.quat`` in
            ``tcp.body``.
        velocity: the joints' speed limits [rad/s or m/s] (MJCF declares none; unbounded
            without).

    Returns:
        The model: one joint per arm joint with the MJCF's position limits (unbounded where
        a joint is not limited) and its actuator's force limit as effort, a frame per
        joint and per body (the MuJoCo names) and the TCP frame.

    Raises:
        RobotDescriptionError: an arm joint is missing, not a hinge or slide, shares its body
            with another joint, has a non-zero reference position, or ``joints`` are not in
            the chain's order; the TCP body is missing or its frame's name is taken.
    """
    import pinocchio as pin

    arm = set(joints)
    found = {model.joint(j).name for j in range(model.njnt)}
    missing = [name for name in joints if name not in found]
    if missing:
        raise RobotDescriptionError(f"arm joints {missing} are not in the MuJoCo model")
    pin_model = pin.Model()
    # MuJoCo body id -> (Pinocchio joint, the body's placement in that joint, its frame).
    bodies: dict[int, tuple[int, Any, int]] = {0: (0, pin.SE3.Identity(), 0)}
    for body in range(1, model.nbody):
        joint, here, frame = bodies[int(model.body_parentid[body])]
        here = here * _placement(model.body_pos[body], model.body_quat[body])
        first, count = int(model.body_jntadr[body]), int(model.body_jntnum[body])
        driven = [j for j in range(first, first + count) if model.joint(j).name in arm]
        if driven:
            if count != 1:
                raise RobotDescriptionError(
                    f"arm joint {model.joint(driven[0]).name!r} shares body "
                    f"{model.body(body).name!r} with another joint"
                )
            joint, frame = _add_joint(pin_model, model, driven[0], joint, here, frame)
            here = pin.SE3(np.eye(3), -np.array(model.jnt_pos[driven[0]]))
        pin_model.appendBodyToJoint(joint, _inertia(model, body), here)
        frame = pin_model.addBodyFrame(model.body(body).name, joint, here, frame)
        bodies[body] = (joint, here, frame)
    if tuple(pin_model.names[1:]) != tuple(joints):
        raise RobotDescriptionError(
            f"arm joints {list(joints)} are not the chain's order {list(pin_model.names[1:])}"
        )
    _add_tcp(pin_model, model, tcp, bodies)
    if velocity is not None:
        pin_model.velocityLimit = np.array(velocity, dtype=float)
    return pin_model


def _placement(pos: np.ndarray, quat: np.ndarray) -> Any:
    import pinocchio as pin

    w, x, y, z = (float(v) for v in quat)
    return pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), np.array(pos, dtype=float))


def _add_joint(
    pin_model: Any, model: mujoco.MjModel, joint: int, parent: int, here: Any, frame: int
) -> tuple[int, int]:
    """Add MuJoCo joint ``joint`` (its body at ``here`` in ``parent``) about its anchor;
    return the Pinocchio joint and its frame."""
    import pinocchio as pin

    spec = model.joint(joint)
    hinge = model.jnt_type[joint] == mujoco.mjtJoint.mjJNT_HINGE
    if not hinge and model.jnt_type[joint] != mujoco.mjtJoint.mjJNT_SLIDE:
        raise RobotDescriptionError(f"arm joint {spec.name!r} is not a hinge or slide joint")
    if model.qpos0[spec.qposadr[0]] != 0.0:
        raise RobotDescriptionError(
            f"arm joint {spec.name!r} has reference position {model.qpos0[spec.qposadr[0]]}: "
            "its MuJoCo and Pinocchio positions would differ by it"
        )
    axis = np.array(spec.axis, dtype=float)
    kind = pin.JointModelRevoluteUnaligned if hinge else pin.JointModelPrismaticUnaligned
    lower, upper = model.jnt_range[joint] if model.jnt_limited[joint] else (-_UNBOUNDED, _UNBOUNDED)
    drives = [
        a
        for a in range(model.nu)
        if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT
        and model.actuator_trnid[a, 0] == spec.id
        and model.actuator_forcelimited[a]
    ]
    effort = float(model.actuator_forcerange[drives[0], 1]) if drives else _UNBOUNDED
    added = pin_model.addJoint(
        parent,
        kind(axis),
        here * pin.SE3(np.eye(3), np.array(spec.pos, dtype=float)),
        spec.name,
        np.array([effort]),
        np.array([_UNBOUNDED]),
        np.array([float(lower)]),
        np.array([float(upper)]),
    )
    return added, pin_model.addJointFrame(added, frame)


def _inertia(model: mujoco.MjModel, body: int) -> Any:
    """The body's spatial inertia in its own frame (MuJoCo's is diagonal in the inertial
    frame ``body_ipos``/``body_iquat``)."""
    import pinocchio as pin

    rotation = _placement(np.zeros(3), model.body_iquat[body]).rotation
    return pin.Inertia(
        float(model.body_mass[body]),
        np.array(model.body_ipos[body], dtype=float),
        rotation @ np.diag(model.body_inertia[body]) @ rotation.T,
    )


def _add_tcp(
    pin_model: Any, model: mujoco.MjModel, tcp: TcpFrame, bodies: dict[int, tuple[int, Any, int]]
) -> None:
    import pinocchio as pin

    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, tcp.body)
    if body < 0:
        raise RobotDescriptionError(f"TCP body {tcp.body!r} is not in the MuJoCo model")
    if pin_model.existFrame(tcp.frame):
        raise RobotDescriptionError(f"TCP frame {tcp.frame!r} names a body or joint already")
    joint, here, frame = bodies[body]
    placement = here * _placement(np.array(tcp.pos), np.array(tcp.quat))
    pin_model.addFrame(pin.Frame(tcp.frame, joint, frame, placement, pin.FrameType.OP_FRAME))
