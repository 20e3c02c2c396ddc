"""The Franka Panda of example-robot-data's ``panda.urdf``, for MuJoCo and Pinocchio alike.

Both simulators load the *same* URDF file, so the kinematics agree by construction (a test
checks TCP pose and Jacobian to 1e-9). Its limits are the URDF's (``check_models`` holds
them to it); the servo gains, armature, gripper drive and home posture are ours.
"""

from __future__ import annotations

import math

import mujoco

from osg_control.control.description import (
    ArmJoints,
    Gripper,
    ModelSource,
    RobotDescription,
    ServoGains,
    TcpFrame,
)
from osg_control.control.robot_model import (
    find_example_robot_data,
    reduced_urdf_model,
    urdf_for_mujoco,
)

URDF = "robots/panda_description/urdf/panda.urdf"
"""The URDF's path inside example-robot-data."""
_PACKAGE_PREFIX = "package://example-robot-data/robots/panda_description/meshes/"
FINGER_JOINTS = ("panda_finger_joint1", "panda_finger_joint2")


def panda_mujoco_spec() -> mujoco.MjSpec:
    """The bare Panda (fingers included) from the URDF, meshes resolved."""
    urdf = find_example_robot_data(URDF)
    text = urdf_for_mujoco(urdf, _PACKAGE_PREFIX, urdf.parent.parent / "meshes")
    return mujoco.MjSpec.from_string(text)


def panda_pinocchio_arm():  # type: ignore[no-untyped-def]
    """The arm-only Pinocchio model (fingers locked) from the same URDF; its frame
    ``panda_hand_tcp`` is the TCP."""
    return reduced_urdf_model(find_example_robot_data(URDF), FINGER_JOINTS)


PANDA = RobotDescription(
    name="panda",
    summary="Franka Panda (example-robot-data URDF), 7 joints, parallel hand",
    model=ModelSource(mujoco=panda_mujoco_spec, pinocchio=panda_pinocchio_arm),
    arm=ArmJoints(
        names=tuple(f"panda_joint{i}" for i in range(1, 8)),
        lower=(-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973),
        upper=(2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973),
        velocity=(2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61),
        effort=(87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0),
        armature=(0.1,) * 7,
    ),
    # kv/kp of about 15 ms, so a 50 ms control step is tracked to within a few per cent.
    servo=ServoGains(
        kp=(4500.0, 4500.0, 3500.0, 3500.0, 2000.0, 2000.0, 2000.0),
        kv=(70.0, 70.0, 50.0, 50.0, 30.0, 30.0, 30.0),
    ),
    # The TCP in the frame of panda_link7: link7 -> link8 (+0.107 z) -> hand (yaw -pi/4) ->
    # tcp (+0.1034 z), all read from the URDF's fixed joints. MuJoCo fuses those static
    # links into panda_link7, so the site is attached there.
    tcp=TcpFrame(
        body="panda_link7",
        pos=(0.0, 0.0, 0.107 + 0.1034),
        quat=(math.cos(-math.pi / 8), 0.0, 0.0, math.sin(-math.pi / 8)),
        frame="panda_hand_tcp",
    ),
    gripper=Gripper(
        joints=FINGER_JOINTS,
        bodies=("panda_leftfinger", "panda_rightfinger"),
        open_position=0.04,
        kp=2000.0,
        kv=100.0,
        force=70.0,  # the Panda hand's continuous grip force [N]
        # Reflected inertia and damping of the hand's drive: without them the 15 g fingers
        # reach metres per second and tunnel through thin parts.
        armature=0.1,
        damping=20.0,
    ),
    home_q=(0.0, -0.785398, 0.0, -2.35619, 0.0, 1.5707, 0.785398),  # the SRDF's ``default``
    control_hz=20.0,
)
"""The example-robot-data Panda (registered as ``panda``)."""
