"""The URDF Panda in MuJoCo and Pinocchio: kinematic agreement and model-file lookup errors."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from osg_control.control import robot_model
from osg_control.control.ik import IKConfig
from osg_control.control.ik_backends import MinkBackend, PinocchioBackend
from osg_control.control.robot_model import HOME_KEY, robot_spec
from osg_control.errors import ModelNotFoundError, OSGError
from osg_control.kitchen import scene
from osg_control.robots.panda import PANDA, URDF, panda_pinocchio_arm

ARM_JOINTS = PANDA.arm.names
HOME_Q = np.array(PANDA.home_q)
TCP_FRAME, TCP_SITE = PANDA.tcp.frame, PANDA.tcp.site

N_CONFIGURATIONS = 100
KINEMATICS_TOL = 1e-9


@pytest.fixture(scope="module")
def mujoco_arm() -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The arm-only MuJoCo model the mink backend uses."""
    model = MinkBackend(IKConfig(backend="mink"), PANDA).model
    return model, mujoco.MjData(model)


@pytest.fixture(scope="module")
def pinocchio_arm() -> tuple[pin.Model, pin.Data]:
    """The arm-only Pinocchio model the Pinocchio backend uses."""
    model = PinocchioBackend(IKConfig(backend="pinocchio"), PANDA).model
    return model, model.createData()


def random_configurations(count: int, seed: int) -> np.ndarray:
    """``count`` arm configurations uniform within the URDF's joint limits."""
    limits = panda_pinocchio_arm()
    rng = np.random.default_rng(seed)
    return rng.uniform(limits.lowerPositionLimit, limits.upperPositionLimit, (count, 7))


def mujoco_tcp(
    model: mujoco.MjModel, data: mujoco.MjData, q: np.ndarray, qpos_index: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """TCP position, rotation and 6x7 world-aligned Jacobian (linear; angular) from MuJoCo."""
    data.qpos[qpos_index] = q
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    site = model.site(TCP_SITE).id
    jacobian = np.zeros((6, model.nv))
    mujoco.mj_jacSite(model, data, jacobian[:3], jacobian[3:], site)
    dofs = [model.joint(name).dofadr[0] for name in ARM_JOINTS]
    return (
        data.site_xpos[site].copy(),
        data.site_xmat[site].reshape(3, 3).copy(),
        jacobian[:, dofs],
    )


def test_joint_limits_agree(
    mujoco_arm: tuple[mujoco.MjModel, mujoco.MjData],
    pinocchio_arm: tuple[pin.Model, pin.Data],
) -> None:
    model, _ = mujoco_arm
    pin_model, _ = pinocchio_arm
    assert model.nq == model.nv == pin_model.nq == pin_model.nv == 7
    np.testing.assert_array_equal(model.jnt_range[:, 0], pin_model.lowerPositionLimit)
    np.testing.assert_array_equal(model.jnt_range[:, 1], pin_model.upperPositionLimit)


def test_tcp_pose_and_jacobian_agree_at_random_configurations(
    mujoco_arm: tuple[mujoco.MjModel, mujoco.MjData],
    pinocchio_arm: tuple[pin.Model, pin.Data],
) -> None:
    model, data = mujoco_arm
    pin_model, pin_data = pinocchio_arm
    frame = pin_model.getFrameId(TCP_FRAME)
    qpos_index = np.array([model.joint(name).qposadr[0] for name in ARM_JOINTS])
    for q in random_configurations(N_CONFIGURATIONS, seed=0):
        pos, rot, jacobian = mujoco_tcp(model, data, q, qpos_index)
        pin_jacobian = pin.computeFrameJacobian(
            pin_model, pin_data, q, frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        pin.updateFramePlacements(pin_model, pin_data)
        placement = pin_data.oMf[frame]
        np.testing.assert_allclose(pos, placement.translation, rtol=0, atol=KINEMATICS_TOL)
        np.testing.assert_allclose(rot, placement.rotation, rtol=0, atol=KINEMATICS_TOL)
        np.testing.assert_allclose(jacobian, pin_jacobian, rtol=0, atol=KINEMATICS_TOL)


def test_kitchen_arm_matches_ik_model(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The simulated arm (mounted at the kitchen's origin) has the IK model's kinematics."""
    monkeypatch.chdir(tmp_path)  # MuJoCo writes its warning log to the working directory
    model = scene.build_kitchen_model(PANDA)
    data = mujoco.MjData(model)
    pin_model = panda_pinocchio_arm()
    pin_data = pin_model.createData()
    frame = pin_model.getFrameId(TCP_FRAME)
    qpos_index = np.array([model.joint(name).qposadr[0] for name in ARM_JOINTS])
    for q in random_configurations(10, seed=1):
        pos, rot, jacobian = mujoco_tcp(model, data, q, qpos_index)
        pin_jacobian = pin.computeFrameJacobian(
            pin_model, pin_data, q, frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        placement = pin_data.oMf[frame]
        np.testing.assert_allclose(pos, placement.translation, rtol=0, atol=KINEMATICS_TOL)
        np.testing.assert_allclose(rot, placement.rotation, rtol=0, atol=KINEMATICS_TOL)
        np.testing.assert_allclose(jacobian, pin_jacobian, rtol=0, atol=KINEMATICS_TOL)


def test_home_keyframe_is_home_q() -> None:
    model = robot_spec(PANDA, with_gripper=True).compile()
    key = model.key(HOME_KEY)
    np.testing.assert_allclose(key.qpos[:7], HOME_Q)
    np.testing.assert_allclose(key.ctrl[:7], HOME_Q)
    np.testing.assert_array_equal(key.ctrl[7:14], 0.0)  # the damping actuators hold still
    assert model.nu == 15  # seven stiffness and seven damping actuators, the gripper


# ------------------------------------------------------------------ model lookup errors
@pytest.fixture
def fresh_find_panda() -> Iterator[None]:
    """Clear ``find_example_robot_data``'s cache before and after, so the real URDF is found
    again."""
    robot_model.find_example_robot_data.cache_clear()
    yield
    robot_model.find_example_robot_data.cache_clear()


def test_missing_urdf_names_every_path_searched(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fresh_find_panda: None
) -> None:
    roots = [tmp_path / "first", tmp_path / "second"]
    monkeypatch.setattr(robot_model, "_example_robot_data_roots", lambda: roots)
    with pytest.raises(ModelNotFoundError) as caught:
        robot_model.find_example_robot_data(URDF)
    message = str(caught.value)
    for root in roots:
        assert str(root / "robots" / "panda_description" / "urdf" / "panda.urdf") in message
    assert "EXAMPLE_ROBOT_DATA_DIR" in message
    assert isinstance(caught.value, FileNotFoundError)
    assert isinstance(caught.value, OSGError)


def test_missing_urdf_under_env_var_is_listed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fresh_find_panda: None
) -> None:
    """``EXAMPLE_ROBOT_DATA_DIR`` is searched first; an empty one shows in the error."""
    monkeypatch.setenv("EXAMPLE_ROBOT_DATA_DIR", str(tmp_path))
    real_roots = robot_model._example_robot_data_roots
    assert real_roots()[0] == tmp_path
    monkeypatch.setattr(robot_model, "_example_robot_data_roots", lambda: real_roots()[:1])
    with pytest.raises(ModelNotFoundError, match=str(tmp_path)):
        robot_model.find_example_robot_data(URDF)


def test_env_var_urdf_takes_precedence(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fresh_find_panda: None
) -> None:
    urdf = tmp_path / "robots" / "panda_description" / "urdf" / "panda.urdf"
    urdf.parent.mkdir(parents=True)
    urdf.write_text("<robot name='panda'/>")
    monkeypatch.setenv("EXAMPLE_ROBOT_DATA_DIR", str(tmp_path))
    assert robot_model.find_example_robot_data(URDF) == urdf


def test_missing_kitchen_scene_names_every_candidate(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    empty = tmp_path / "robots_dir"
    empty.mkdir()
    monkeypatch.setenv("OSG_ROBOTS_DIR", str(empty))
    # The repository fallback is PACKAGE_DIR.parent / "robots": point it at a bare folder.
    monkeypatch.setattr(scene, "PACKAGE_DIR", tmp_path / "checkout" / "osg_control")
    with pytest.raises(ModelNotFoundError) as caught:
        scene.build_kitchen_model(PANDA)
    message = str(caught.value)
    assert str(empty / "kitchen.xml") in message
    assert str(tmp_path / "checkout" / "robots" / "kitchen.xml") in message


def test_osg_robots_dir_takes_precedence(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    shutil.copy(scene.kitchen_xml_path(), tmp_path / "kitchen.xml")
    monkeypatch.setenv("OSG_ROBOTS_DIR", str(tmp_path))
    assert scene.kitchen_xml_path() == tmp_path / "kitchen.xml"
