"""The lifted observation and action of an object-moving operator (``pick`` /
``pick-out``): everything in the operand's frame, so one network serves every object of
any type.

Observation (``OBS_FIELDS``), from the percept and the scene's static description only:
the TCP minus the grasp point (``grasp.grasp_point``: where the scripted grasp closes) and
minus the object's perceived origin, the object's upright half-extents, the sine and
cosine of the wrist's yaw error to the grasp rotation (``grasp.grasp_rotation``), the
finger opening, the last gripper command and for how many steps it has been given (the
skill's own memory, up to ``HELD_STEPS``: the fingers take steps to close), and how far
the object has risen since the operator started.

Action (``ACTION_FIELDS``): the TCP's target offset [m] (world axes, centred on the TCP),
the wrist's yaw offset about the vertical [rad] and the gripper command, bounded by
``ACTION_SCALE``. ``command`` turns one into the TCP target ``drive.JointTargetDriver``
drives; ``lifted_action`` turns a scripted controller's target into one, so the data
record exactly what was commanded.
"""

from __future__ import annotations

import numpy as np

from osg_control.libero.drive import GRIPPER_CLOSED, GRIPPER_OPEN
from osg_control.libero.grasp import grasp_point, grasp_rotation
from osg_control.libero.legs import Context, yawed
from osg_control.libero.perception import LiberoPercept

OBS_FIELDS = (
    "tcp_minus_grasp_x", "tcp_minus_grasp_y", "tcp_minus_grasp_z",
    "tcp_minus_object_x", "tcp_minus_object_y", "tcp_minus_object_z",
    "half_extent_x", "half_extent_y", "half_extent_z",
    "yaw_error_sin", "yaw_error_cos", "finger_width", "last_gripper", "gripper_held",
    "object_rise",
)  # fmt: skip
"""The lifted observation's features, in order (positions in m, world axes)."""
ACTION_FIELDS = ("tcp_dx", "tcp_dy", "tcp_dz", "wrist_dyaw", "gripper")
"""The lifted action's components, in order."""
ACTION_SCALE = np.array([0.03, 0.03, 0.03, 0.3, 1.0])
"""The largest action component: a TCP target 3 cm away per axis (more than the arm
covers in a 50 ms step at the controller's 0.05 rad joint limit), a 0.3 rad wrist turn,
and the gripper command (robosuite's: -1 opens, 1 closes)."""
OBS_DIM, ACTION_DIM = len(OBS_FIELDS), len(ACTION_FIELDS)
HELD_STEPS = 60
"""``gripper_held`` counts the steps the last gripper command has been given up to this,
as a fraction of it: longer than the scripted pick's descent (40 steps), after which it
closes wherever the hand is (a tall bottle stops the fingertips 1.3 cm above the grasp
point; at 20 the learned pick could not tell when to close there and hovered)."""


class GripperMemory:
    """The skill's last gripper command and for how many steps it has been given."""

    def __init__(self) -> None:
        self.last, self.held = GRIPPER_OPEN, 0

    def given(self, command: float) -> None:
        """Note the command sent this step."""
        self.held = self.held + 1 if command == self.last else 1
        self.last = command


def _yaw(ctx: Context, rotation: np.ndarray) -> float:
    """A hand rotation's turn about the vertical from the episode's top-down start."""
    relative = rotation @ ctx.base.T
    return float(np.arctan2(relative[1, 0], relative[0, 0]))


def _wrapped(angle: float) -> float:
    return float((angle + np.pi) % (2 * np.pi) - np.pi)


def observe(
    ctx: Context, percept: LiberoPercept, obj: str, start_z: float, gripper: GripperMemory
) -> np.ndarray:
    """The lifted observation of moving ``obj`` (``OBS_FIELDS``), float32."""
    pos, _ = percept.objects[obj]
    low, high = ctx.scene.extents[obj]
    _, hand = ctx.driver.tcp_pose(percept.joints)
    error = _wrapped(_yaw(ctx, grasp_rotation(ctx, percept, obj)) - _yaw(ctx, hand))
    return np.concatenate([
        percept.tcp - grasp_point(ctx, percept, obj), percept.tcp - pos, (high - low) / 2,
        [np.sin(error), np.cos(error), percept.finger_width, gripper.last,
         min(gripper.held, HELD_STEPS) / HELD_STEPS, pos[2] - start_z],
    ]).astype(np.float32)  # fmt: skip


def lifted_action(
    ctx: Context, percept: LiberoPercept, position: np.ndarray, rotation: np.ndarray,
    gripper: float,
) -> np.ndarray:  # fmt: skip
    """A TCP target and gripper command as the lifted action, each component clipped into
    ``ACTION_SCALE``."""
    _, hand = ctx.driver.tcp_pose(percept.joints)
    turn = _wrapped(_yaw(ctx, rotation) - _yaw(ctx, hand))
    action = np.r_[position - percept.tcp, turn, gripper]
    return np.clip(action, -ACTION_SCALE, ACTION_SCALE)


def command(
    ctx: Context, percept: LiberoPercept, action: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float]:
    """The TCP target (position, top-down rotation) and gripper command of a lifted
    action, clipped into ``ACTION_SCALE`` (the gripper's sign: open or closed).

    Raises:
        ValueError: an action of the wrong shape or with a NaN or infinity.
    """
    action = np.asarray(action, dtype=float)
    if action.shape != (ACTION_DIM,) or not np.all(np.isfinite(action)):
        raise ValueError(f"a lifted action is {ACTION_DIM} finite numbers, got {action!r}")
    action = np.clip(action, -ACTION_SCALE, ACTION_SCALE)
    _, hand = ctx.driver.tcp_pose(percept.joints)
    yaw = _yaw(ctx, hand) + action[3]
    rotation = yawed(yaw) @ ctx.base
    gripper = GRIPPER_CLOSED if action[4] > 0 else GRIPPER_OPEN
    return percept.tcp + action[:3], rotation, gripper
