"""Version checks and one compatibility fix for Gymnasium-Robotics' FrankaKitchen-v1.

The fix. ``gymnasium_robotics.utils.mujoco_utils.get_joint_qpos`` / ``get_joint_qvel``
(1.4.x) check a hinge or slide joint with
``assert joint_type in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE)``, where
``joint_type = model.jnt_type[j]`` is an ``np.int32``. ``in`` compares with the tuple's
items first (``mjtJoint.mjJNT_HINGE == np.int32(3)``), and from mujoco 3.12 on that
comparison is False (the reverse one is still True), so the assertion fails and
``gymnasium.make("FrankaKitchen-v1")`` raises ``AssertionError`` while building its first
observation. ``apply_compat_fix`` replaces the two functions in that module, only when the
comparison is broken, by ones that take the same slice of ``qpos`` / ``qvel`` with the joint
type compared as a plain ``int``: the env reads exactly the numbers it would have read on an
older mujoco, and its step, reward, noise and task-completion code run as shipped.
"""

from __future__ import annotations

from importlib import metadata
from typing import Any

import numpy as np

from osg_control.errors import DomainError

GYMNASIUM_ROBOTICS_RANGE = ((1, 4), (1, 5))
"""Tested ``gymnasium-robotics`` versions: >= 1.4, < 1.5 (the ``franka`` extra's range)."""
MUJOCO_RANGE = ((3, 3), (5, 0))
"""Tested ``mujoco`` versions: >= 3.3, < 5 (the fix is needed from 3.12 on)."""
ORIGINALS: dict[str, Any] = {}
"""The library's own functions, kept when ``apply_compat_fix`` replaces them (for tests)."""
_QPOS_WIDTH = {0: 7, 1: 4}
"""Free joint: 7 qpos (position, quaternion); ball joint: 4. Hinge and slide: 1."""
_QVEL_WIDTH = {0: 6, 1: 4}
"""Free joint: 6 dofs; ball joint: 4 (the library's width, kept). Hinge and slide: 1."""


def _version_tuple(text: str) -> tuple[int, ...]:
    parts = []
    for piece in text.split(".")[:3]:
        digits = "".join(c for c in piece if c.isdigit())
        parts.append(int(digits) if digits else 0)
    return tuple(parts)


def _check_range(package: str, version: str, bounds: tuple[tuple[int, ...], ...]) -> None:
    low, high = bounds
    if not low <= _version_tuple(version) < high:
        raise DomainError(
            f"franka-kitchen: {package} {version} is outside the tested range "
            f">={'.'.join(map(str, low))},<{'.'.join(map(str, high))}; install "
            f"osg-control[franka] to get a tested one"
        )


def check_versions() -> None:
    """Refuse a missing or untested ``gymnasium-robotics`` or ``mujoco``.

    Raises:
        DomainError: naming the package, its version and the tested range.
    """
    try:
        robotics = metadata.version("gymnasium-robotics")
    except metadata.PackageNotFoundError as err:
        raise DomainError(
            "franka-kitchen needs gymnasium-robotics: pip install 'osg-control[franka]'"
        ) from err
    _check_range("gymnasium-robotics", robotics, GYMNASIUM_ROBOTICS_RANGE)
    _check_range("mujoco", metadata.version("mujoco"), MUJOCO_RANGE)


def comparison_bug_present() -> bool:
    """Whether ``np.int32`` joint types fail the library's ``in (mjJNT_HINGE, ...)`` test."""
    import mujoco

    hinge = mujoco.mjtJoint.mjJNT_HINGE
    return np.int32(int(hinge)) not in (hinge, mujoco.mjtJoint.mjJNT_SLIDE)


def _joint(model: Any, name: str) -> tuple[int, int]:
    import mujoco

    joint_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
    if joint_id == -1:
        raise AssertionError(f"Joint with name '{name}' is not part of the model!")
    return joint_id, int(model.jnt_type[joint_id])


def joint_qpos(model: Any, data: Any, name: str) -> np.ndarray:
    """A copy of joint ``name``'s qpos (7 free, 4 ball, 1 hinge or slide)."""
    joint_id, kind = _joint(model, name)
    start = int(model.jnt_qposadr[joint_id])
    return data.qpos[start : start + _QPOS_WIDTH.get(kind, 1)].copy()


def joint_qvel(model: Any, data: Any, name: str) -> np.ndarray:
    """A copy of joint ``name``'s qvel (6 free, 4 ball as the library takes, 1 otherwise)."""
    joint_id, kind = _joint(model, name)
    start = int(model.jnt_dofadr[joint_id])
    width = _QVEL_WIDTH.get(kind, 1)
    return data.qvel[start : start + width].copy()


def apply_compat_fix() -> bool:
    """Patch ``mujoco_utils.get_joint_qpos/qvel`` if (and only if) the bug is present.

    Idempotent. Returns True when the patched functions are in place.
    """
    from gymnasium_robotics.utils import mujoco_utils

    if not comparison_bug_present():
        return False
    if mujoco_utils.get_joint_qpos is not joint_qpos:
        ORIGINALS["get_joint_qpos"] = mujoco_utils.get_joint_qpos
        ORIGINALS["get_joint_qvel"] = mujoco_utils.get_joint_qvel
    mujoco_utils.get_joint_qpos = joint_qpos
    mujoco_utils.get_joint_qvel = joint_qvel
    return True


def prepare() -> None:
    """Check versions, apply the fix where needed and register the library's envs."""
    check_versions()
    import gymnasium
    import gymnasium_robotics

    apply_compat_fix()
    gymnasium.register_envs(gymnasium_robotics)
