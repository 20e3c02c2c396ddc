"""``control.mujoco_pinocchio``: a Pinocchio arm built from a compiled MuJoCo model holds
MuJoCo's kinematics and inertias to rounding, and refuses what it cannot represent."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from osg_control.control.description import RobotDescriptionError, TcpFrame
from osg_control.control.mujoco_pinocchio import pinocchio_arm_from_mujoco

TOL = 1e-12
"""Both sides compose the same double-precision poses: they differ by rounding only
(measured about 1e-15 on this arm and on FrankaKitchen's Panda)."""

# Orientations given as euler angles in degrees, an axisangle and an off-origin hinge anchor:
# what MuJoCo's compiler resolves and the builder must take from the compiled model.
ARM_XML = """
<mujoco>
  <compiler angle="degree" eulerseq="XYZ"/>
  <worldbody>
    <body name="base" pos="0.1 -0.2 0.3" euler="0 0 30">
      <inertial pos="0 0 0.05" mass="2" diaginertia="0.01 0.02 0.03"/>
      <body name="link1" pos="0 0 0.2" euler="10 20 33.3">
        <joint name="j1" axis="0 0 1" range="-170 170"/>
        <inertial pos="0.01 0 0.1" quat="0.9 0.1 0.2 0.3" mass="1.5" diaginertia="0.02 0.03 0.04"/>
        <body name="link2" pos="0.05 0.01 0.3" axisangle="1 1 0 57.2957795">
          <joint name="j2" axis="0 1 0" pos="0 0 -0.04" range="-90 90"/>
          <inertial pos="0 0.02 0.1" mass="1.2" diaginertia="0.01 0.015 0.02"/>
          <body name="slider" pos="0 0 0.25" quat="0.7 0 0.7 0.1">
            <joint name="j3" type="slide" axis="1 0 0" range="-0.1 0.1"/>
            <inertial pos="0.03 0 0" mass="0.8" diaginertia="0.004 0.005 0.006"/>
            <body name="finger" pos="0 0.03 0.05">
              <joint name="f1" type="slide" axis="0 1 0" range="0 0.04"/>
              <inertial pos="0 0 0.02" mass="0.1" diaginertia="1e-4 1e-4 1e-4"/>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
JOINTS = ("j1", "j2", "j3")
TCP = TcpFrame(body="slider", pos=(0.02, -0.01, 0.12), quat=(0.8, 0.0, 0.6, 0.0), frame="tool")


def _arm_dofs(model: mujoco.MjModel) -> list[int]:
    return [int(model.joint(j).dofadr[0]) for j in JOINTS]


def test_kinematics_and_inertias_are_mujocos() -> None:
    model = mujoco.MjModel.from_xml_string(ARM_XML)
    pin_model = pinocchio_arm_from_mujoco(model, JOINTS, TCP, velocity=(1.0, 2.0, 0.5))
    assert tuple(pin_model.names[1:]) == JOINTS and pin_model.nq == 3
    np.testing.assert_array_equal(pin_model.velocityLimit, [1.0, 2.0, 0.5])
    ranges = np.array([model.joint(j).range for j in JOINTS])
    np.testing.assert_array_equal(pin_model.lowerPositionLimit, ranges[:, 0])
    np.testing.assert_array_equal(pin_model.upperPositionLimit, ranges[:, 1])
    assert all(pin_model.existFrame(b) for b in ("base", "link1", "link2", "slider", "finger"))
    # The TCP as a MuJoCo site, placed as the core places it (``robot_model.robot_spec``).
    spec = mujoco.MjSpec.from_string(ARM_XML)
    spec.body(TCP.body).add_site(name="tcp", pos=TCP.pos, quat=TCP.quat)
    model = spec.compile()
    data = mujoco.MjData(model)
    pin_data = pin_model.createData()
    frame = pin_model.getFrameId(TCP.frame)
    dofs = _arm_dofs(model)
    rng = np.random.default_rng(0)
    for _ in range(20):
        q = rng.uniform(pin_model.lowerPositionLimit, pin_model.upperPositionLimit)
        data.qpos[:] = 0.0
        data.qpos[[int(model.joint(j).qposadr[0]) for j in JOINTS]] = q
        mujoco.mj_forward(model, data)
        pin.computeJointJacobians(pin_model, pin_data, q)
        pin.framesForwardKinematics(pin_model, pin_data, q)
        pose = pin_data.oMf[frame]
        np.testing.assert_allclose(pose.translation, data.site("tcp").xpos, rtol=0, atol=TOL)
        np.testing.assert_allclose(
            pose.rotation, data.site("tcp").xmat.reshape(3, 3), rtol=0, atol=TOL
        )
        jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
        mujoco.mj_jacSite(model, data, jacp, jacr, model.site("tcp").id)
        jacobian = pin.getFrameJacobian(
            pin_model, pin_data, frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        np.testing.assert_allclose(jacobian[:3], jacp[:, dofs], rtol=0, atol=TOL)
        np.testing.assert_allclose(jacobian[3:], jacr[:, dofs], rtol=0, atol=TOL)
        # The arm's block of MuJoCo's mass matrix is that of the arm with the finger welded.
        full = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, full)
        mass = pin.crba(pin_model, pin_data, q)
        mass = np.triu(mass) + np.triu(mass, 1).T
        np.testing.assert_allclose(mass, full[np.ix_(dofs, dofs)], rtol=0, atol=TOL)


@pytest.mark.parametrize(
    ("edit", "joints", "tcp", "message"),
    [
        (None, ("j1", "j9", "j3"), TCP, r"arm joints \['j9'\] are not in the MuJoCo model"),
        (None, ("j2", "j1", "j3"), TCP, "are not the chain's order"),
        (('name="j2" axis', 'name="j2" ref="5" axis'), JOINTS, TCP, "reference position"),
        (
            ('type="slide" axis="1 0 0" range="-0.1 0.1"', 'type="ball"'),
            JOINTS,
            TCP,
            "not a hinge or slide",
        ),
        (
            ('<inertial pos="0.03', '<joint name="j4" axis="0 0 1"/><inertial pos="0.03'),
            JOINTS,
            TCP,
            "shares body 'slider' with another joint",
        ),
        (None, JOINTS, TcpFrame("hand", (0, 0, 0), (1, 0, 0, 0), "tool"), "TCP body 'hand'"),
        (None, JOINTS, TcpFrame("slider", (0, 0, 0), (1, 0, 0, 0), "link1"), "names a body"),
    ],
)
def test_what_it_cannot_represent_is_refused(
    edit: tuple[str, str] | None, joints: tuple[str, ...], tcp: TcpFrame, message: str
) -> None:
    xml = ARM_XML.replace(*edit) if edit else ARM_XML
    with pytest.raises(RobotDescriptionError, match=message):
        pinocchio_arm_from_mujoco(mujoco.MjModel.from_xml_string(xml), joints, tcp)
