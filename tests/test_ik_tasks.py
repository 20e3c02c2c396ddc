"""The IK QP's open lists: a task or limit a user adds enters the QP as it does in mink's
and Pink's ``build_ik``, on both backends."""

from __future__ import annotations

import mink
import numpy as np
import pink
import pinocchio as pin
import pytest
import qpsolvers
from pink.limits import ConfigurationLimit, VelocityLimit
from test_ik import assert_is_reference, random_cases, required
from toy_robot import TOY

from osg_control.control.description import RobotDescription
from osg_control.control.ik import DiffIKController, IKConfig
from osg_control.control.ik_tasks import (
    DampingTask,
    IKState,
    Limit,
    PostureTask,
    ResidualTask,
)
from osg_control.errors import ControllerError
from osg_control.robots.panda import PANDA

ELBOW = 3
"""The joint ``ElbowTask`` pulls (the Panda's fourth)."""


class ElbowTask(ResidualTask):
    """A task written in the test, as a user would: one joint toward a value (one error
    row, its Jacobian a unit row)."""

    def __init__(self, value: float, cost: float, gain: float = 1.0) -> None:
        super().__init__(cost, gain)
        self.value = value

    def residual(self, state: IKState) -> tuple[np.ndarray, np.ndarray]:
        row = np.zeros((1, state.q.size))
        row[0, ELBOW] = 1.0
        return np.array([state.q[ELBOW] - self.value]), row


class StepCap(Limit):
    """A limit written in the test: the first joint moves at most ``step`` [rad] a solve."""

    def __init__(self, step: float) -> None:
        self.step = step

    def box(self, state: IKState) -> tuple[np.ndarray, np.ndarray]:
        upper = np.full(state.q.size, np.inf)
        upper[0] = self.step
        return -upper, upper


def user_parts(robot: RobotDescription) -> tuple[list, list]:
    """The tasks and limits a user adds: a second posture task (another target, per-joint
    weights), damping, the elbow task, and the step cap."""
    n = robot.n_joints
    other = np.array(robot.home_q) + np.linspace(-0.2, 0.2, n)
    tasks = [
        PostureTask(other, np.linspace(0.05, 0.1, n), gain=0.5),
        DampingTask(0.03),
        ElbowTask(-2.0, 0.2, gain=0.8),
    ]
    return tasks, [StepCap(1e-3)]


@pytest.mark.parametrize("robot", [PANDA, TOY], ids=["panda", "toy6"])
def test_user_tasks_and_limits_enter_the_qp_as_in_minks_build_ik(
    robot: RobotDescription,
) -> None:
    """Our QP with the user's parts equals ``mink.build_ik`` with the same tasks and
    limits written in mink (the elbow task as a ``PostureTask`` weighted on that joint
    only, the step cap as a ``VelocityLimit``), and its solution obeys the cap."""
    config = IKConfig(backend="mink")
    tasks, limits = user_parts(robot)
    controller = DiffIKController(robot, config, tasks=tasks, limits=limits)
    plain = DiffIKController(robot, config)
    backend = controller.backend
    model = backend.model  # type: ignore[attr-defined]
    frame = mink.FrameTask(
        robot.tcp.site, "site", position_cost=1.0, orientation_cost=0.5, lm_damping=1e-6
    )
    posture = mink.PostureTask(model, cost=config.posture_cost)
    posture.set_target(np.array(robot.home_q))
    second = mink.PostureTask(model, cost=np.linspace(0.05, 0.1, robot.n_joints), gain=0.5)
    second.set_target(tasks[0].target)  # type: ignore[attr-defined]
    elbow_cost = np.zeros(robot.n_joints)
    elbow_cost[ELBOW] = 0.2
    elbow = mink.PostureTask(model, cost=elbow_cost, gain=0.8)
    elbow.set_target(np.full(robot.n_joints, -2.0))
    names = [model.joint(i).name for i in range(model.njnt)]
    mink_limits = [
        mink.ConfigurationLimit(model, gain=config.limit_gain),
        mink.VelocityLimit(model, dict(zip(names, backend.velocity_limit, strict=True))),
        mink.VelocityLimit(model, {names[0]: 1e-3 / config.dt}),
    ]
    configuration = mink.Configuration(model)
    for q, pos, rot in random_cases(controller, 20, seed=7):
        configuration.update(q)
        frame.set_target(mink.SE3.from_rotation_and_translation(mink.SO3.from_matrix(rot), pos))
        reference = mink.build_ik(
            configuration,
            [frame, posture, second, mink.DampingTask(model, 0.03), elbow],
            config.dt,
            damping=config.damping,
            limits=mink_limits,
        )
        ours = backend.build_qp(q, pos, rot, hard_tcp=False)
        assert_is_reference(ours, reference)
        velocity = controller.solve_velocity(q, pos, rot)
        expected = required(qpsolvers.solve_problem(reference, solver="daqp").x) / config.dt
        np.testing.assert_allclose(velocity, expected, rtol=0, atol=1e-6)
        assert abs(velocity[0]) * config.dt <= 1e-3 + 1e-9
        # The parts change the QP: without them the Hessian lacks their weights.
        without = plain.backend.build_qp(q, pos, rot, hard_tcp=False)
        assert np.abs(ours.P - without.P).max() > 1e-3


@pytest.mark.parametrize("robot", [PANDA, TOY], ids=["panda", "toy6"])
def test_user_tasks_build_the_same_qp_on_pinocchio_as_pinks_build_ik(
    robot: RobotDescription,
) -> None:
    """With a damping task and a second scalar-weighted posture task (Pink's own), the
    Pinocchio backend's QP is ``pink.build_ik``'s, in tracking and in a joint reset (the
    TCP task held as an equality), and the mink backend's QP is the same."""
    config = IKConfig(backend="pinocchio")
    other = np.array(robot.home_q) + 0.1
    tasks = [PostureTask(other, 0.07, gain=0.5), DampingTask(0.03)]
    controller = DiffIKController(robot, config, tasks=tasks)
    mink_twin = DiffIKController(robot, IKConfig(backend="mink"), tasks=tasks)
    model = controller.backend.model  # type: ignore[attr-defined]
    frame = pink.FrameTask(robot.tcp.frame, position_cost=1.0, orientation_cost=0.5)
    frame.lm_damping = config.lm_damping
    posture = pink.PostureTask(cost=config.posture_cost)
    posture.set_target(np.array(robot.home_q))
    second = pink.PostureTask(cost=0.07, gain=0.5)
    second.set_target(other)
    extra = [second, pink.tasks.DampingTask(0.03)]
    limits = [ConfigurationLimit(model, config_limit_gain=config.limit_gain), VelocityLimit(model)]
    for hard_tcp in (False, True):
        for q, target_pos, target_rot in random_cases(controller, 10, seed=8):
            pos, rot = controller.tcp_pose(q) if hard_tcp else (target_pos, target_rot)
            frame.set_target(pin.SE3(rot, pos))
            reference = pink.build_ik(
                pink.Configuration(model, model.createData(), q),
                [posture, *extra] if hard_tcp else [frame, posture, *extra],
                config.dt,
                damping=config.damping,
                limits=limits,
                constraints=[frame] if hard_tcp else None,
            )
            ours = controller.backend.build_qp(q, pos, rot, hard_tcp)
            assert_is_reference(ours, reference)
            twin = mink_twin.backend.build_qp(q, pos, rot, hard_tcp)
            np.testing.assert_allclose(twin.P, ours.P, rtol=0, atol=1e-9)
            np.testing.assert_allclose(twin.q, ours.q, rtol=0, atol=1e-9)


def test_a_damping_task_adds_its_weight_to_the_hessian_alone() -> None:
    """``DampingTask(w)`` adds ``w^2 I`` to the Hessian and nothing else, and slows the arm."""
    plain = DiffIKController(PANDA)
    damped = DiffIKController(PANDA, tasks=[DampingTask(0.5)])
    for q, pos, rot in random_cases(plain, 5, seed=9):
        a, b = (c.backend.build_qp(q, pos, rot, False) for c in (plain, damped))
        np.testing.assert_allclose(b.P - a.P, 0.25 * np.eye(7), rtol=0, atol=1e-12)
        np.testing.assert_array_equal(b.q, a.q)
        slow, fast = (np.linalg.norm(c.solve_velocity(q, pos, rot)) for c in (damped, plain))
        assert slow < fast


@pytest.mark.parametrize(
    ("parts", "message"),
    [
        ({"tasks": [PostureTask(np.zeros(6), 0.1)]}, "PostureTask target: has 6 values for 7"),
        ({"tasks": [DampingTask(np.ones(3))]}, "DampingTask cost: has 3 values for 7"),
        ({"tasks": [PostureTask(np.zeros(7), np.ones(2))]}, "PostureTask cost: has 2 values"),
    ],
)
def test_parts_sized_for_another_arm_are_refused(parts: dict, message: str) -> None:
    with pytest.raises(ControllerError, match=message):
        DiffIKController(PANDA, **parts)


@pytest.mark.parametrize(
    "build",
    [
        lambda: DampingTask(-1.0),
        lambda: DampingTask(float("nan")),
        lambda: PostureTask(np.full(7, np.inf), 0.1),
        lambda: PostureTask(np.zeros(7), 0.1, gain=2.0),
        lambda: ElbowTask(0.0, cost=-0.2),
    ],
)
def test_bad_task_weights_are_refused(build: object) -> None:
    with pytest.raises(ControllerError):
        build()  # type: ignore[operator]


def test_a_task_without_an_equality_cannot_be_a_constraint() -> None:
    q = np.array(PANDA.home_q)
    ik = DiffIKController(PANDA)
    state = IKState(q, *ik.tcp_pose(q), ik.backend)
    with pytest.raises(ControllerError, match="DampingTask cannot be held as an equality"):
        DampingTask(0.1).equality(state)
