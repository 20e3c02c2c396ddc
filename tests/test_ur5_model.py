"""The UR5 with its parallel gripper: MuJoCo and Pinocchio agree, the home posture is sound,
the gripper lifts a 4.5 cm box in MuJoCo physics, and missing files are named."""

from __future__ import annotations

import mink
import mujoco
import numpy as np
import pinocchio as pin
import pytest

from osg_control.control.description import (
    ORIGIN,
    Placement,
    RobotDescription,
    RobotDescriptionError,
    mounted,
)
from osg_control.control.reach import reach_pose
from osg_control.control.robot_model import (
    GRIPPER_ACTUATOR,
    HOME_KEY,
    pinocchio_arm,
    robot_spec,
)
from osg_control.control.scene_model import with_robot
from osg_control.control.servo import DAMPING_SUFFIX
from osg_control.domain.spec import TOP_DOWN_QUAT
from osg_control.kitchen.scene import ROBOT_MOUNTS
from osg_control.robots import ur5_model
from osg_control.robots.registry import get_robot
from osg_control.robots.ur5_model import ARM_JOINTS, FINGER_JOINTS, HOME_Q, TCP_FRAME

KITCHEN_BASE = ROBOT_MOUNTS["ur5"]
TCP_SITE = "tcp"

KINEMATICS_TOL = 1e-9


def ur5_at(base: Placement) -> RobotDescription:
    """The registered UR5 mounted at ``base``."""
    return mounted(get_robot("ur5"), base)


@pytest.fixture(scope="module")
def arm_model() -> mujoco.MjModel:
    """The arm-only model an IK backend uses, mounted as in the kitchen."""
    return robot_spec(ur5_at(KITCHEN_BASE), with_gripper=False).compile()


@pytest.fixture(scope="module")
def full_model() -> mujoco.MjModel:
    return robot_spec(ur5_at(KITCHEN_BASE), with_gripper=True).compile()


def random_configurations(count: int, seed: int) -> np.ndarray:
    lower, upper = ur5_model.joint_limits()
    return np.random.default_rng(seed).uniform(lower, upper, (count, len(ARM_JOINTS)))


def mujoco_tcp(model: mujoco.MjModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """TCP position, rotation and 6 x 6 world-aligned Jacobian (linear; angular), as mink
    (the IK backend on the MuJoCo model) computes them."""
    configuration = mink.Configuration(model)
    qpos = configuration.q.copy()
    qpos[[model.joint(name).qposadr[0] for name in ARM_JOINTS]] = q
    configuration.update(qpos)
    pose = configuration.get_transform_frame_to_world(TCP_SITE, "site")
    rotation = pose.rotation().as_matrix()
    local = configuration.get_frame_jacobian(TCP_SITE, "site")
    aligned = np.vstack([rotation @ local[:3], rotation @ local[3:]])
    dofs = [model.joint(name).dofadr[0] for name in ARM_JOINTS]
    return pose.translation(), rotation, aligned[:, dofs]


def test_limits_come_from_the_urdf(full_model: mujoco.MjModel) -> None:
    pin_model = ur5_model.load_pinocchio_arm()
    assert pin_model.nq == len(ARM_JOINTS) == 6
    lower, upper = ur5_model.joint_limits()
    for i, name in enumerate(ARM_JOINTS):
        joint = full_model.joint(name)
        np.testing.assert_array_equal(joint.range, [lower[i], upper[i]])
        effort = ur5_model.effort_limits()[i]
        np.testing.assert_array_equal(full_model.jnt_actfrcrange[joint.id], [-effort, effort])
    np.testing.assert_array_equal(ur5_model.velocity_limits(), [3.15, 3.15, 3.15, 3.2, 3.2, 3.2])
    np.testing.assert_array_equal(ur5_model.effort_limits(), [150, 150, 150, 28, 28, 28])


@pytest.mark.parametrize("base", [ORIGIN, KITCHEN_BASE, ((0.3, -0.2, 0.5), (0.6, 0.0, 0.0, 0.8))])
def test_tcp_pose_and_jacobian_agree_at_random_configurations(base: Placement) -> None:
    """MuJoCo's TCP site (arm-only and gripper models) and Pinocchio's TCP frame, with the
    base mounted alike (``robot_model.robot_spec``, ``robot_model.pinocchio_arm``)."""
    robot = ur5_at(base)
    arm_model = robot_spec(robot, with_gripper=False).compile()
    full_model = robot_spec(robot, with_gripper=True).compile()
    pin_model = pinocchio_arm(robot)
    pin_data = pin_model.createData()
    frame = pin_model.getFrameId(TCP_FRAME)
    for q in random_configurations(50, seed=0):
        pin_jacobian = pin.computeFrameJacobian(
            pin_model, pin_data, q, frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        pin.updateFramePlacements(pin_model, pin_data)
        placement = pin_data.oMf[frame]
        for model in (arm_model, full_model):
            pos, rot, jacobian = mujoco_tcp(model, q)
            np.testing.assert_allclose(pos, placement.translation, rtol=0, atol=KINEMATICS_TOL)
            np.testing.assert_allclose(rot, placement.rotation, rtol=0, atol=KINEMATICS_TOL)
            np.testing.assert_allclose(jacobian, pin_jacobian, rtol=0, atol=KINEMATICS_TOL)


def test_the_bare_spec_is_links_joints_and_the_finger_coupling() -> None:
    """What a robot description's MuJoCo builder returns: no actuator, site or key."""
    model = ur5_model.ur5_bare_spec().compile()
    assert (model.nu, model.nsite, model.nkey, model.neq) == (0, 0, 0, 1)
    joints = [model.joint(i).name for i in range(model.njnt)]
    assert joints == [*ARM_JOINTS, *FINGER_JOINTS]
    np.testing.assert_array_equal(model.joint(FINGER_JOINTS[0]).range, [0, ur5_model.FINGER_OPEN])
    assert model.nexclude == len(ur5_model.disabled_collision_pairs()) == 10


@pytest.mark.parametrize(
    "base",
    [((0.0, 0.0), (1.0, 0.0, 0.0, 0.0)), ((0.0, np.nan, 0.0), (1.0, 0.0, 0.0, 0.0)),
     ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0))],
)  # fmt: skip
def test_a_bad_mount_is_refused(base: Placement) -> None:
    with pytest.raises(RobotDescriptionError, match="field 'mount'"):
        ur5_at(base)


def test_tcp_is_between_the_pads(full_model: mujoco.MjModel) -> None:
    """The TCP lies midway between the pads' centres, on the closing axis (its y)."""
    data = mujoco.MjData(full_model)
    mujoco.mj_resetDataKeyframe(full_model, data, full_model.key(HOME_KEY).id)
    mujoco.mj_forward(full_model, data)
    site = data.site(TCP_SITE)
    left = data.geom("left_finger_pad").xpos
    right = data.geom("right_finger_pad").xpos
    np.testing.assert_allclose((left + right) / 2, site.xpos, atol=1e-9)
    axis = site.xmat.reshape(3, 3)[:, 1]
    np.testing.assert_allclose(left - right, axis * (np.linalg.norm(left - right)), atol=1e-9)
    pad_width = 2 * full_model.geom("left_finger_pad").size[1]
    assert np.linalg.norm(left - right) - pad_width == pytest.approx(ur5_model.MAX_OPENING)


def test_home_posture(full_model: mujoco.MjModel) -> None:
    """The home key holds ``HOME_Q`` (inside the limits) with the fingers open, and puts the
    TCP pointing down at the kitchen's home node with the base at ``KITCHEN_BASE``."""
    lower, upper = ur5_model.joint_limits()
    assert np.all(HOME_Q > lower) and np.all(HOME_Q < upper)
    key = full_model.key(HOME_KEY)
    np.testing.assert_array_equal(key.qpos, [*HOME_Q, *[ur5_model.FINGER_OPEN] * 2])
    np.testing.assert_array_equal(key.ctrl[:6], HOME_Q)
    np.testing.assert_array_equal(key.ctrl[6:12], 0.0)
    assert full_model.actuator(ARM_JOINTS[0] + DAMPING_SUFFIX).id == 6
    assert key.ctrl[full_model.actuator(GRIPPER_ACTUATOR).id] == ur5_model.FINGER_OPEN
    position, rotation, _ = mujoco_tcp(full_model, HOME_Q)
    np.testing.assert_allclose(position, [0.35, 0.0, 0.45], atol=5e-4)
    np.testing.assert_allclose(rotation[:, 2], [0.0, 0.0, -1.0], atol=1e-3)
    assert full_model.body_gravcomp[0] == 0.0 and np.all(full_model.body_gravcomp[1:] == 1.0)


# ------------------------------------------------------------------ grasp in MuJoCo physics
BOX_HALF = 0.0225
BOX_AT = (0.5, -0.2)


def _grasp_scene() -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The UR5 at ``KITCHEN_BASE`` on a table top (z = 0) with a 4.5 cm, 80 g box on it
    where the kitchen's cube is."""
    spec = mujoco.MjSpec()
    spec.option.timestep = 0.002
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = 10
    spec.default.geom.solref = [0.004, 1.0]  # stiff contacts, as the kitchen's
    spec.default.geom.solimp = [0.95, 0.99, 0.001, 0.5, 2.0]
    spec.worldbody.add_geom(
        name="table", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.7, 0.8, 0.05], pos=[0.35, 0, -0.05]
    )
    box = spec.worldbody.add_body(name="box", pos=[*BOX_AT, BOX_HALF])
    box.add_freejoint()
    box.add_geom(
        name="box",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[BOX_HALF] * 3,
        mass=0.08,
        friction=[1.5, 0.02, 0.001],
        condim=4,
    )
    with_robot(spec, ur5_at(KITCHEN_BASE))
    model = spec.compile()
    data = mujoco.MjData(model)
    data.qpos[[model.joint(n).qposadr[0] for n in ARM_JOINTS]] = HOME_Q
    data.qpos[[model.joint(n).qposadr[0] for n in FINGER_JOINTS]] = ur5_model.FINGER_OPEN
    data.ctrl[[model.actuator(n).id for n in ARM_JOINTS]] = HOME_Q
    data.ctrl[model.actuator(GRIPPER_ACTUATOR).id] = ur5_model.FINGER_OPEN
    return model, data


def _move(model: mujoco.MjModel, data: mujoco.MjData, goal: np.ndarray, seconds: float) -> None:
    """Ramp the arm's joint targets to ``goal`` over ``seconds``, then settle 0.5 s."""
    actuators = [model.actuator(n).id for n in ARM_JOINTS]
    start = data.ctrl[actuators].copy()
    steps = int(seconds / model.opt.timestep)
    for i in range(steps + int(0.5 / model.opt.timestep)):
        data.ctrl[actuators] = start + (goal - start) * min(1.0, (i + 1) / steps)
        mujoco.mj_step(model, data)


@pytest.mark.filterwarnings("ignore:Attaching a spec with an empty prefix")
def test_gripper_closes_on_and_lifts_a_box(arm_model: mujoco.MjModel) -> None:
    model, data = _grasp_scene()
    limits = dict(zip(ARM_JOINTS, ur5_model.velocity_limits(), strict=True))
    above = reach_pose(arm_model, TCP_SITE, (*BOX_AT, 0.15), TOP_DOWN_QUAT, HOME_Q, limits)
    grasp = reach_pose(arm_model, TCP_SITE, (*BOX_AT, BOX_HALF), TOP_DOWN_QUAT, above.q, limits)
    assert above.reached() and grasp.reached()
    box = model.body("box").id
    gripper = model.actuator(GRIPPER_ACTUATOR).id
    _move(model, data, above.q, 2.0)
    _move(model, data, grasp.q, 1.5)
    np.testing.assert_allclose(data.xpos[box], [*BOX_AT, BOX_HALF], atol=2e-3)  # not pushed
    data.ctrl[gripper] = 0.0
    _move(model, data, grasp.q, 0.5)
    width = sum(data.qpos[model.joint(n).qposadr[0]] for n in FINGER_JOINTS)
    assert width == pytest.approx(2 * BOX_HALF, abs=2e-3)  # closed on the box, not past it
    np.testing.assert_allclose(data.xpos[box], data.site(TCP_SITE).xpos, atol=1e-3)  # centred
    _move(model, data, above.q, 1.5)
    assert data.xpos[box][2] > BOX_HALF + 0.1  # lifted with the hand (TCP 0.15 above the table)
    tcp = data.site(TCP_SITE).xpos
    assert np.linalg.norm(data.xpos[box] - tcp) < 0.01  # held at the TCP, not dangling
    pads = {"left_finger_pad", "right_finger_pad"}
    touching = {model.geom(g).name for pair in data.contact.geom for g in pair} & pads
    assert touching == pads


@pytest.mark.filterwarnings("ignore:Attaching a spec with an empty prefix")
def test_drives_track_a_bounded_action_path(arm_model: mujoco.MjModel) -> None:
    """Joint targets from the IK every 50 ms along a 2 cm-per-step path (the kitchen's action
    bound): the simulated TCP stays within 1 cm of the IK's, the joints under their speed
    limits, and it ends on it."""
    model, data = _grasp_scene()
    limits = ur5_model.velocity_limits()
    by_name = dict(zip(ARM_JOINTS, limits, strict=True))
    goal = (0.4, 0.35, 0.2)
    reach = reach_pose(arm_model, TCP_SITE, goal, TOP_DOWN_QUAT, HOME_Q, by_name, 60, max_step=0.02)
    assert reach.reached()
    actuators = [model.actuator(n).id for n in ARM_JOINTS]
    dofs = [model.joint(n).dofadr[0] for n in ARM_JOINTS]
    substeps = round(0.05 / model.opt.timestep)
    ik_data = mujoco.MjData(arm_model)
    lag, peak = [], 0.0
    for q in reach.path:
        data.ctrl[actuators] = q
        for _ in range(substeps):
            mujoco.mj_step(model, data)
            peak = max(peak, float(np.max(np.abs(data.qvel[dofs]) / limits)))
        ik_data.qpos[:] = q
        mujoco.mj_kinematics(arm_model, ik_data)
        lag.append(np.linalg.norm(data.site(TCP_SITE).xpos - ik_data.site(TCP_SITE).xpos))
    assert max(lag) < 0.01 and lag[-1] < 1e-3
    assert peak < 1.0


def test_reach_reports_an_unreachable_pose_and_refuses_bad_input(
    arm_model: mujoco.MjModel,
) -> None:
    limits = dict(zip(ARM_JOINTS, ur5_model.velocity_limits(), strict=True))
    far = reach_pose(arm_model, TCP_SITE, (2.0, 0.0, 0.3), TOP_DOWN_QUAT, HOME_Q, limits, steps=100)
    assert not far.reached() and far.position_error > 0.9
    assert far.path.shape == (100, 6) and np.array_equal(far.path[-1], far.q)
    with pytest.raises(ValueError, match="non-finite"):
        reach_pose(arm_model, TCP_SITE, (np.nan, 0.0, 0.3), TOP_DOWN_QUAT, HOME_Q, limits)
    with pytest.raises(ValueError, match="shape"):
        reach_pose(arm_model, TCP_SITE, (0.4, 0.0, 0.3), TOP_DOWN_QUAT, HOME_Q[:5], limits)
    with pytest.raises(ValueError, match="max_step"):
        reach_pose(arm_model, TCP_SITE, (0.4, 0, 0.3), TOP_DOWN_QUAT, HOME_Q, limits, max_step=0)


def test_max_step_walks_the_straight_line(arm_model: mujoco.MjModel) -> None:
    """With ``max_step`` the TCP follows the line to the goal at most that far per step."""
    limits = dict(zip(ARM_JOINTS, ur5_model.velocity_limits(), strict=True))
    goal = np.array([0.5, -0.2, 0.15])
    reach = reach_pose(arm_model, TCP_SITE, goal, TOP_DOWN_QUAT, HOME_Q, limits, 60, max_step=0.02)
    assert reach.reached()
    data = mujoco.MjData(arm_model)
    points = []
    for q in reach.path:
        data.qpos[:] = q
        mujoco.mj_kinematics(arm_model, data)
        points.append(data.site(TCP_SITE).xpos.copy())
    start = np.array([0.35, 0.0, 0.45])
    line = (goal - start) / np.linalg.norm(goal - start)
    off_line = [np.linalg.norm((p - start) - line * np.dot(p - start, line)) for p in points]
    assert max(off_line) < 5e-3
    assert np.max(np.linalg.norm(np.diff(points, axis=0), axis=1)) < 0.021
