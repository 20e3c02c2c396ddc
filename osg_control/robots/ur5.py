"""The UR5 of example-robot-data's ``ur5_robot.urdf`` with a 2F-85-like parallel gripper
(``ur5_model``), as a ``RobotDescription`` (registered as ``ur5``).

Its limits are the URDF's (``check_models`` holds them to it); the servo gains, armature,
gripper drive and home posture are ``ur5_model``'s. Where it stands in a scene is the
domain's to say (``Domain.mounts``): the home kitchen mounts it at (0.10, 0.15, 0)
(``kitchen.scene.ROBOT_MOUNTS``).
"""

from __future__ import annotations

from osg_control.control import description as rd
from osg_control.robots import ur5_model as m


def _floats(values: object) -> tuple[float, ...]:
    return tuple(float(v) for v in values)  # type: ignore[attr-defined]


def ur5_description() -> rd.RobotDescription:
    """The UR5 (its limits read from the URDF)."""
    lower, upper = m.joint_limits()
    tcp_pos, tcp_quat = m.tcp_in_flange()
    return rd.RobotDescription(
        name="ur5",
        summary="Universal Robots UR5 (example-robot-data URDF), 6 joints, 2F-85-like gripper",
        model=rd.ModelSource(mujoco=m.ur5_bare_spec, pinocchio=m.load_pinocchio_arm),
        arm=rd.ArmJoints(
            names=m.ARM_JOINTS,
            lower=_floats(lower),
            upper=_floats(upper),
            velocity=_floats(m.velocity_limits()),
            effort=_floats(m.effort_limits()),
            armature=m.ARM_ARMATURE,
        ),
        servo=rd.ServoGains(kp=m.SERVO_KP, kv=m.SERVO_KV),
        tcp=rd.TcpFrame(body=m.TCP_BODY, pos=tcp_pos, quat=tcp_quat, frame=m.TCP_FRAME),
        gripper=rd.Gripper(
            joints=m.FINGER_JOINTS,
            bodies=m.FINGER_BODIES,
            open_position=m.FINGER_OPEN,
            kp=m.GRIPPER_KP,
            kv=m.GRIPPER_KV,
            force=m.GRIP_FORCE,
            armature=m.FINGER_ARMATURE,
            damping=m.FINGER_DAMPING,
        ),
        home_q=_floats(m.HOME_Q),
        control_hz=20.0,
        # sensors: the default (encoders, finger width, grip force): the 2F-85 reports its
        # fingers' position and motor current, read here from the actuator's force.
    )
