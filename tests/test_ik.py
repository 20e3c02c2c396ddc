"""The differential-IK controller: one QP for both backends, convergence, limits, joint reset."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import mink
import numpy as np
import pink
import pinocchio as pin
import pytest
import qpsolvers
from pink.limits import ConfigurationLimit, VelocityLimit
from scipy.spatial.transform import Rotation
from toy_robot import TOY

from osg_control.control.description import RobotDescription
from osg_control.control.ik import (
    DiffIKController,
    IKConfig,
    joint_reset_controller,
    solve_ik,
)
from osg_control.control.ik_backends import MinkBackend, PinocchioBackend
from osg_control.control.rotations import rotation_error, rotation_step
from osg_control.errors import ControllerError
from osg_control.robots.panda import PANDA

BACKEND_NAMES = ("mink", "pinocchio")
HOME_Q = np.array(PANDA.home_q)
TCP_FRAME, TCP_SITE = PANDA.tcp.frame, PANDA.tcp.site
SHOULDER = np.array([0.0, 0.0, 0.333])
LIMIT_TOL = 1e-9
"""Slack on joint position [rad] and velocity [rad/s] limits: DAQP's primal tolerance is
1e-6 on ``dq`` only in the worst case; in practice it meets bounds to ~1e-11."""
OSQP_TOL = 1e-4
"""DAQP vs OSQP (``osqp_eps = 1e-9``) agreement [rad/s or m/s]; see ``test_daqp_and_osqp``."""


@pytest.fixture(scope="module")
def controllers() -> dict[str, DiffIKController]:
    """A default controller per backend (DAQP)."""
    return {name: DiffIKController(PANDA, IKConfig(backend=name)) for name in BACKEND_NAMES}


@pytest.fixture(scope="module")
def reset_controllers() -> dict[str, DiffIKController]:
    """A joint-reset controller per backend."""
    return {name: joint_reset_controller(PANDA, IKConfig(backend=name)) for name in BACKEND_NAMES}


def random_cases(
    controller: DiffIKController, count: int, seed: int, reach: float = 0.05
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(q, target position, target rotation) near home; targets within ``reach`` [m]."""
    rng = np.random.default_rng(seed)
    lower, upper = controller.backend.lower + 0.02, controller.backend.upper - 0.02
    cases = []
    for _ in range(count):
        home = controller.posture
        q = np.clip(home + rng.normal(0.0, 0.4, home.size), lower, upper)
        pos, rot = controller.tcp_pose(q)
        target_rot = rotation_step(rot, rng.normal(0.0, 0.1, 3))
        cases.append((q, pos + rng.normal(0.0, reach, 3), target_rot))
    return cases


def assert_same_problem(first: qpsolvers.Problem, second: qpsolvers.Problem, tol: float) -> None:
    """Equal Hessian, linear term, bounds and equalities, to ``tol``."""
    for name in ("P", "q", "lb", "ub", "A", "b"):
        a, b = getattr(first, name), getattr(second, name)
        assert (a is None) == (b is None), name
        if a is not None:
            np.testing.assert_allclose(a, b, rtol=0, atol=tol, err_msg=name)


def required(value: np.ndarray | None) -> np.ndarray:
    """``value``, which must be set."""
    assert value is not None
    return value


def box_from_inequalities(problem: qpsolvers.Problem) -> tuple[np.ndarray, np.ndarray]:
    """The box ``lb <= dq <= ub`` implied by rows ``+-e_i dq <= h`` (mink's and Pink's form)."""
    n = required(problem.P).shape[0]
    lower, upper = np.full(n, -np.inf), np.full(n, np.inf)
    for row, bound in zip(required(problem.G), required(problem.h), strict=True):
        (index,) = np.flatnonzero(row)
        if row[index] > 0:
            upper[index] = min(upper[index], bound / row[index])
        else:
            lower[index] = max(lower[index], bound / row[index])
    return lower, upper


def assert_is_reference(ours: qpsolvers.Problem, reference: qpsolvers.Problem) -> None:
    """Our QP is a library's ``build_ik`` to 1e-12: Hessian, linear term, the box its
    ``+-I`` inequality rows imply, and its equality rows if it has any."""
    np.testing.assert_allclose(ours.P, reference.P, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ours.q, reference.q, rtol=0, atol=1e-12)
    lower, upper = box_from_inequalities(reference)
    np.testing.assert_allclose(required(ours.lb), lower, rtol=0, atol=1e-12)
    np.testing.assert_allclose(required(ours.ub), upper, rtol=0, atol=1e-12)
    assert (ours.A is None) == (reference.A is None)
    if reference.A is not None:
        np.testing.assert_allclose(required(ours.A), reference.A, rtol=0, atol=1e-12)
        np.testing.assert_allclose(required(ours.b), required(reference.b), rtol=0, atol=1e-12)


# ------------------------------------------------------------------ one QP, two backends
@pytest.mark.parametrize("hard_tcp", [False, True])
def test_backends_build_the_same_qp(
    controllers: dict[str, DiffIKController],
    reset_controllers: dict[str, DiffIKController],
    hard_tcp: bool,
) -> None:
    group = reset_controllers if hard_tcp else controllers
    mink_ik, pin_ik = group["mink"], group["pinocchio"]
    for q, target_pos, target_rot in random_cases(mink_ik, 40, seed=1):
        # A reachable equality for the joint reset: hold the current TCP pose.
        pos, rot = mink_ik.tcp_pose(q) if hard_tcp else (target_pos, target_rot)
        assert_same_problem(
            mink_ik.backend.build_qp(q, pos, rot, hard_tcp),
            pin_ik.backend.build_qp(q, pos, rot, hard_tcp),
            tol=1e-9,
        )
        np.testing.assert_allclose(
            mink_ik.solve_velocity(q, pos, rot, hard_tcp),
            pin_ik.solve_velocity(q, pos, rot, hard_tcp),
            rtol=0,
            atol=1e-6,
        )


AXIS_COSTS = {
    "scalar": {},
    "per-axis": {"position_cost": (1.0, 0.8, 1.2), "orientation_cost": (0.5, 0.5, 0.0)},
}
"""The frame task's weights: the defaults, and one per TCP axis with the yaw relaxed."""


@pytest.mark.parametrize("costs", AXIS_COSTS.values(), ids=AXIS_COSTS.keys())
@pytest.mark.parametrize("robot", [PANDA, TOY], ids=["panda", "toy6"])
def test_qp_is_minks_build_ik(robot: RobotDescription, costs: dict[str, Any]) -> None:
    """The shared assembly reproduces ``mink.build_ik`` with mink's own tasks and limits,
    for seven joints and for six, with one weight for three axes or one per axis."""
    config = IKConfig(backend="mink", **costs)
    backend = MinkBackend(config, robot)
    controller = DiffIKController(robot, config)
    configuration = mink.Configuration(backend.model)
    frame_task = mink.FrameTask(
        robot.tcp.site,
        "site",
        position_cost=config.position_cost,
        orientation_cost=config.orientation_cost,
        gain=config.gain,
        lm_damping=config.lm_damping,
    )
    posture_task = mink.PostureTask(backend.model, cost=config.posture_cost, gain=config.gain)
    posture_task.set_target(np.array(robot.home_q))
    names = [backend.model.joint(i).name for i in range(backend.model.njnt)]
    limits = [
        mink.ConfigurationLimit(backend.model, gain=config.limit_gain),
        mink.VelocityLimit(backend.model, dict(zip(names, backend.velocity_limit, strict=True))),
    ]
    for q, pos, rot in random_cases(controller, 20, seed=2):
        configuration.update(q)
        frame_task.set_target(
            mink.SE3.from_rotation_and_translation(mink.SO3.from_matrix(rot), pos)
        )
        reference = mink.build_ik(
            configuration,
            [frame_task, posture_task],
            config.dt,
            damping=config.damping,
            limits=limits,
        )
        assert_is_reference(backend.build_qp(q, pos, rot, hard_tcp=False), reference)
        expected = required(qpsolvers.solve_problem(reference, solver="daqp").x) / config.dt
        np.testing.assert_allclose(
            controller.solve_velocity(q, pos, rot), expected, rtol=0, atol=1e-6
        )


@pytest.mark.parametrize("costs", AXIS_COSTS.values(), ids=AXIS_COSTS.keys())
@pytest.mark.parametrize("robot", [PANDA, TOY], ids=["panda", "toy6"])
def test_qp_is_pinks_build_ik(robot: RobotDescription, costs: dict[str, Any]) -> None:
    """The Pinocchio backend's QP is ``pink.build_ik`` with Pink's tasks and limits, for
    seven joints and for six, with one weight for three axes or one per axis."""
    config = IKConfig(backend="pinocchio", **costs)
    backend = PinocchioBackend(config, robot)
    model = backend.model
    frame_task = pink.FrameTask(
        robot.tcp.frame,
        position_cost=config.position_cost,
        orientation_cost=config.orientation_cost,
        lm_damping=config.lm_damping,
        gain=config.gain,
    )
    posture_task = pink.PostureTask(cost=config.posture_cost, gain=config.gain)
    posture_task.set_target(np.array(robot.home_q))
    limits = [ConfigurationLimit(model, config_limit_gain=config.limit_gain), VelocityLimit(model)]
    controller = DiffIKController(robot, config)
    for hard_tcp in (False, True):
        for q, target_pos, target_rot in random_cases(controller, 20, seed=3):
            pos, rot = controller.tcp_pose(q) if hard_tcp else (target_pos, target_rot)
            configuration = pink.Configuration(model, model.createData(), q)
            frame_task.set_target(pin.SE3(rot, pos))
            reference = pink.build_ik(
                configuration,
                [posture_task] if hard_tcp else [frame_task, posture_task],
                config.dt,
                damping=config.damping,
                limits=limits,
                constraints=[frame_task] if hard_tcp else None,
            )
            assert_is_reference(backend.build_qp(q, pos, rot, hard_tcp), reference)


@pytest.mark.parametrize("backend", BACKEND_NAMES)
def test_daqp_and_osqp(
    controllers: dict[str, DiffIKController],
    reset_controllers: dict[str, DiffIKController],
    backend: str,
) -> None:
    """OSQP matches DAQP to ``OSQP_TOL`` wherever the QP is well conditioned.

    With the default posture cost (1e-3) the Hessian's curvature along the arm's 1-D null
    space is only ~1e-6, so OSQP's residual tolerance pins the null-space part of ``v``
    loosely (observed up to ~2e-2 rad/s in 1 of 600 random QPs); what the TCP does
    (``J v``) agrees to ``OSQP_TOL`` (observed <= 6e-7). The joint-reset QP (posture cost 1)
    agrees to ``OSQP_TOL`` in full (observed <= 3e-8 rad/s).
    """
    daqp_ik = controllers[backend]
    osqp_ik = DiffIKController(PANDA, IKConfig(backend=backend, solver="osqp"))
    for q, pos, rot in random_cases(daqp_ik, 40, seed=4):
        v_daqp = daqp_ik.solve_velocity(q, pos, rot)
        v_osqp = osqp_ik.solve_velocity(q, pos, rot)
        _, jacobian = daqp_ik.backend.frame_residual(q, pos, rot)
        np.testing.assert_allclose(jacobian @ v_osqp, jacobian @ v_daqp, rtol=0, atol=OSQP_TOL)
        np.testing.assert_allclose(v_osqp, v_daqp, rtol=0, atol=0.05)
    daqp_reset = reset_controllers[backend]
    osqp_reset = joint_reset_controller(PANDA, IKConfig(backend=backend, solver="osqp"))
    for q, _, _ in random_cases(daqp_ik, 40, seed=5):
        pos, rot = daqp_ik.tcp_pose(q)
        np.testing.assert_allclose(
            osqp_reset.solve_velocity(q, pos, rot, hard_tcp=True),
            daqp_reset.solve_velocity(q, pos, rot, hard_tcp=True),
            rtol=0,
            atol=OSQP_TOL,
        )


def test_osqp_solves_are_independent_of_history() -> None:
    """The reused OSQP workspace gives a fresh one's answer (to rounding: no warm start)."""
    used = DiffIKController(PANDA, IKConfig(solver="osqp"))
    cases = random_cases(used, 10, seed=6)
    for q, pos, rot in cases[1:]:
        used.solve_velocity(q, pos, rot)
    fresh = DiffIKController(PANDA, IKConfig(solver="osqp"))
    np.testing.assert_allclose(
        used.solve_velocity(*cases[0]), fresh.solve_velocity(*cases[0]), rtol=0, atol=1e-12
    )


def test_mink_kinematics_reused_only_at_the_same_q() -> None:
    """The mink backend skips forward kinematics when its configuration is at ``q``
    already, and redoes it for any other ``q``: every answer equals a fresh backend's bit
    for bit, whatever was asked before (a pose then a residual at the same q, as a relative
    step does, or a residual at another q, including one edited in place)."""
    used = MinkBackend(IKConfig(), PANDA)
    cases = random_cases(DiffIKController(PANDA), 6, seed=11)
    for q, pos, rot in cases:
        fresh = MinkBackend(IKConfig(), PANDA)
        for got, want in zip(used.tcp_pose(q), fresh.tcp_pose(q), strict=True):
            np.testing.assert_array_equal(got, want)
        for got, want in zip(
            used.frame_residual(q, pos, rot), fresh.frame_residual(q, pos, rot), strict=True
        ):
            np.testing.assert_array_equal(got, want)
    q, pos, rot = cases[0]
    moved = q.copy()
    used.frame_residual(moved, pos, rot)
    moved[3] += 0.1  # the same array, edited: not the configuration's q any more
    for got, want in zip(
        used.frame_residual(moved, pos, rot),
        MinkBackend(IKConfig(), PANDA).frame_residual(moved, pos, rot),
        strict=True,
    ):
        np.testing.assert_array_equal(got, want)


# ------------------------------------------------------------------ convergence and limits
def assert_within_limits(controller: DiffIKController, q: np.ndarray) -> None:
    backend = controller.backend
    assert np.all(q >= backend.lower - LIMIT_TOL) and np.all(q <= backend.upper + LIMIT_TOL), q


def pose_error(controller: DiffIKController, q: np.ndarray, pos: np.ndarray, rot: np.ndarray):  # type: ignore[no-untyped-def]
    """Position [m] and orientation [rad] error of the TCP at ``q``."""
    current_pos, current_rot = controller.tcp_pose(q)
    return (
        float(np.linalg.norm(current_pos - pos)),
        float(np.linalg.norm(rotation_error(current_rot, rot))),
    )


@pytest.mark.parametrize("backend", BACKEND_NAMES)
def test_ik_reaches_random_reachable_targets(
    controllers: dict[str, DiffIKController], backend: str
) -> None:
    """50 targets from FK of random in-limit configurations (home +- 1 rad), from HOME_Q."""
    controller = controllers[backend]
    lower, upper = controller.backend.lower, controller.backend.upper
    rng = np.random.default_rng(7)
    for _ in range(50):
        target_q = np.clip(HOME_Q + rng.uniform(-1.0, 1.0, 7), lower + 0.02, upper - 0.02)
        pos, rot = controller.tcp_pose(target_q)
        q = HOME_Q.copy()
        for _ in range(200):  # solve_ik's loop, checking every iterate
            q = controller.step(q, pos, rot)
            assert_within_limits(controller, q)
            velocity = controller.solve_velocity(q, pos, rot)
            assert np.all(np.abs(velocity) <= controller.backend.velocity_limit + LIMIT_TOL)
            assert_within_limits(controller, q + velocity * controller.config.dt)
            if max(pose_error(controller, q, pos, rot)) < 1e-5:
                break
        position_error, orientation_error = pose_error(controller, q, pos, rot)
        assert position_error < 2e-3 and orientation_error < 0.02
        solved, converged = solve_ik(controller, HOME_Q, pos, rot)
        assert converged
        assert_within_limits(controller, solved)
        position_error, orientation_error = pose_error(controller, solved, pos, rot)
        assert position_error < 2e-3 and orientation_error < 0.02


@pytest.mark.parametrize("backend", BACKEND_NAMES)
def test_frame_task_error_decreases_strictly(
    controllers: dict[str, DiffIKController], backend: str
) -> None:
    controller = controllers[backend]
    start = HOME_Q + np.array([0.2, 0.1, -0.1, -0.2, 0.1, 0.2, -0.1])
    pos, rot = controller.tcp_pose(HOME_Q)
    q = start
    errors = []
    for _ in range(30):
        error, _ = controller.backend.frame_residual(q, pos, rot)
        errors.append(float(np.linalg.norm(error)))
        q = controller.step(q, pos, rot)
    assert errors[0] > 0.1
    still_moving = [e for e in errors if e > 1e-9]
    assert len(still_moving) >= 3
    assert np.all(np.diff(still_moving) < 0), errors
    assert errors[-1] < 1e-7


@pytest.mark.parametrize("backend", BACKEND_NAMES)
def test_unreachable_target_respects_limits(
    controllers: dict[str, DiffIKController], backend: str
) -> None:
    """A target 2 m away: the arm stretches toward it within position and velocity limits."""
    controller = controllers[backend]
    limits = controller.backend.velocity_limit
    q = HOME_Q.copy()
    pos, rot = controller.tcp_pose(q)
    target = pos + np.array([2.0, 0.0, 0.0])
    for _ in range(100):
        velocity = controller.solve_velocity(q, target, rot)
        assert np.all(np.abs(velocity) <= limits + LIMIT_TOL), velocity / limits
        assert_within_limits(controller, q + velocity * controller.config.dt)
        q = controller.step(q, target, rot)
        assert_within_limits(controller, q)
    final, _ = controller.tcp_pose(q)
    assert np.linalg.norm(final - target) < np.linalg.norm(pos - target) - 0.5
    assert np.linalg.norm(final - SHOULDER) > 0.85  # arm stretched out


# ------------------------------------------------------------------ joint reset
@pytest.mark.parametrize("backend", BACKEND_NAMES)
def test_reset_step_holds_tcp_and_approaches_posture(
    reset_controllers: dict[str, DiffIKController], backend: str
) -> None:
    reset = reset_controllers[backend]
    # Move the joints away from home along the self-motion manifold of the home TCP pose,
    # by a joint reset toward another posture.
    away = HOME_Q + np.array([0.6, 0.0, -0.6, 0.0, 0.4, 0.0, -0.4])
    pusher = joint_reset_controller(PANDA, replace(reset.config, posture=tuple(away)))
    pos, rot = reset.tcp_pose(HOME_Q)
    q = HOME_Q.copy()
    for _ in range(40):
        q = pusher.reset_step(q, pos, rot)
    posture = reset.posture
    distances = [float(np.linalg.norm(q - posture))]
    assert distances[0] > 0.3
    for _ in range(20):
        q = reset.reset_step(q, pos, rot)
        distances.append(float(np.linalg.norm(q - posture)))
        position_error, orientation_error = pose_error(reset, q, pos, rot)
        assert position_error < 2e-3 and orientation_error < 0.02
    assert np.all(np.diff(distances[:9]) < 0), distances
    assert distances[-1] < 0.1 * distances[0]


# ------------------------------------------------------------------ API details
def test_rotation_helpers_match_scipy() -> None:
    rng = np.random.default_rng(8)
    for seed in range(50):
        rot = Rotation.random(random_state=seed).as_matrix()
        target = Rotation.random(random_state=seed + 100).as_matrix()
        delta = rng.normal(0.0, 0.5, 3) if seed else np.zeros(3)
        np.testing.assert_allclose(
            rotation_step(rot, delta),
            Rotation.from_rotvec(delta).as_matrix() @ rot,
            rtol=0,
            atol=1e-12,
        )
        np.testing.assert_allclose(
            rotation_error(rot, target),
            Rotation.from_matrix(target @ rot.T).as_rotvec(),
            rtol=0,
            atol=1e-9,
        )


def test_relative_step_is_step_toward_the_moved_pose(
    controllers: dict[str, DiffIKController],
) -> None:
    controller = controllers["mink"]
    delta = np.array([0.01, -0.005, 0.01, 0.05, 0.0, -0.05])
    pos, rot = controller.tcp_pose(HOME_Q)
    np.testing.assert_array_equal(
        controller.relative_step(HOME_Q, delta),
        controller.step(HOME_Q, pos + delta[:3], rotation_step(rot, delta[3:])),
    )


def test_bad_inputs_raise_controller_error(controllers: dict[str, DiffIKController]) -> None:
    controller = controllers["mink"]
    pos, rot = controller.tcp_pose(HOME_Q)
    bad_q = HOME_Q.copy()
    bad_q[2] = np.nan
    with pytest.raises(ControllerError):
        controller.solve_velocity(bad_q, pos, rot)
    with pytest.raises(ControllerError):
        controller.solve_velocity(HOME_Q[:6], pos, rot)
    with pytest.raises(ControllerError):
        controller.solve_velocity(HOME_Q, pos + np.inf, rot)
    with pytest.raises(ControllerError):
        controller.solve_velocity(HOME_Q, pos[:2], rot)
    with pytest.raises(ControllerError):
        controller.relative_step(HOME_Q, np.full(6, np.nan))
    with pytest.raises(ControllerError):
        controller.relative_step(HOME_Q, np.zeros(7))


@pytest.mark.parametrize(
    "options",
    [{"backend": "drake"}, {"solver": "quadprog-typo"}, {"gain": 0.0}],
)
def test_invalid_config_raises(options: dict[str, object]) -> None:
    with pytest.raises(ControllerError):
        IKConfig(**options)  # type: ignore[arg-type]


@pytest.mark.parametrize("backend", BACKEND_NAMES)
def test_posture_of_another_arm_is_refused(backend: str) -> None:
    """A posture is checked against the robot's joints when the controller is built."""
    with pytest.raises(ControllerError, match="posture has 6 values, robot 'panda' has 7"):
        DiffIKController(PANDA, IKConfig(backend=backend, posture=(0.0,) * 6))


@pytest.mark.parametrize("backend", ["mink", "pinocchio"])
def test_a_relaxed_axis_leaves_its_error_out_of_the_qp(backend: str) -> None:
    """With no weight on the rotation about the TCP's z axis (a six-joint arm giving up
    yaw), a target turned only about that axis pulls as the current pose does: the QP's
    linear term is the posture's alone (its Hessian still differs: ``Jlog6`` of the error
    couples the other rows), where the default weights pull toward the turn."""
    config = IKConfig(backend=backend, orientation_cost=(0.5, 0.5, 0.0))
    controller = DiffIKController(TOY, config)
    for q, _, _ in random_cases(controller, 10, seed=5):
        pos, rot = controller.tcp_pose(q)
        turned = rot @ Rotation.from_rotvec([0.0, 0.0, 0.3]).as_matrix()
        here, yawed = (controller.backend.build_qp(q, pos, r, False) for r in (rot, turned))
        np.testing.assert_allclose(yawed.q, here.q, rtol=0, atol=1e-12)
        weighted = DiffIKController(TOY, IKConfig(backend=backend)).backend
        assert np.abs(weighted.build_qp(q, pos, turned, False).q - here.q).max() > 1e-3


@pytest.mark.parametrize("cost", [(1.0, 2.0), -0.5, float("nan"), "high", (1.0, 1.0, -1.0)])
def test_a_frame_weight_that_is_not_one_or_three_numbers_is_refused(cost: Any) -> None:
    with pytest.raises(ControllerError, match="IKConfig.orientation_cost must be one or three"):
        IKConfig(orientation_cost=cost)
