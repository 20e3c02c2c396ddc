"""Robots as data: a toy arm defined here runs the kitchen with no core edit; descriptions
are validated with named errors; the registry and ``osg robots`` list them."""

from __future__ import annotations

import dataclasses
import json
import logging
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from toy_robot import TOY

from osg_control import cli
from osg_control.control.description import (
    ArmJoints,
    RobotDescription,
    RobotDescriptionError,
    ServoGains,
)
from osg_control.control.ik import DiffIKController, IKConfig, solve_ik
from osg_control.control.ik_backends import MinkBackend, PinocchioBackend
from osg_control.control.robot_model import (
    check_models,
)
from osg_control.data.scripted import ScriptedPolicy
from osg_control.domain.registry import get_domain
from osg_control.environment.arm_env import EnvConfig
from osg_control.kitchen.env import KitchenEnv
from osg_control.perception.spec import perception_spec
from osg_control.robots import registry
from osg_control.robots.panda import PANDA


@pytest.fixture
def toy_registered(monkeypatch: pytest.MonkeyPatch) -> Iterator[RobotDescription]:
    """``TOY`` in the registry for one test (the registry as before after it)."""
    monkeypatch.setattr(registry, "_REGISTERED", dict(registry._REGISTERED))
    monkeypatch.setattr(registry, "_LOADED", dict(registry._LOADED))
    registry.register_robot(TOY)
    yield registry.get_robot("toy6")


# ------------------------------------------------------------------ a toy arm in the kitchen
def test_the_toy_arm_matches_its_models() -> None:
    check_models(TOY)
    assert TOY.n_joints == 6 and not TOY.redundant


@pytest.mark.parametrize("robot", [TOY, "ur5"], ids=["toy6", "ur5"])
@pytest.mark.parametrize("skill", ["move-home-to-cube", "grab-cube"])
def test_a_six_joint_arm_runs_kitchen_episodes(skill: str, robot: RobotDescription | str) -> None:
    """Algorithm 1's scripted policy reaches the skill's goal with a six-joint arm, the toy
    arm defined in the tests or the registered UR5 at its kitchen mount (success on the
    simulator's truth), under the robot perception (encoders of six joints)."""
    spec = get_domain("kitchen").skill(skill)
    env = KitchenEnv(skill=spec, robot=robot)
    obs, info = env.reset(seed=3)
    assert info["arm_q"].shape == (6,) and env.percept().joints.shape == (6,)
    policy = ScriptedPolicy(spec, np.random.default_rng(3), bounds=env.action_bounds)
    policy.reset()
    for _ in range(spec.max_steps or 100):
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        assert np.isfinite(obs).all() and "failure" not in info
        if terminated or truncated:
            break
    assert reward == 1.0 and env.skill_success()
    env.close()


def test_a_six_joint_arm_under_the_robot_perception() -> None:
    """The encoders read six noisy joints and the TCP follows a +x command."""
    config = EnvConfig(perception=perception_spec("robot"))
    env = KitchenEnv(skill="move-home-to-door", config=config, robot=TOY)
    env.reset(seed=0)
    start = env.tcp_pose()[0]
    for _ in range(5):
        _, _, _, _, info = env.step(np.array([0.02, 0, 0, 0, 0, 0, 0]))
    percept = info["percept"]
    assert percept.joints.shape == (6,) and not np.array_equal(percept.joints, env.arm_q)
    assert env.tcp_pose()[0][0] - start[0] > 0.05


def test_the_joint_reset_says_a_six_joint_arm_has_no_null_space(
    caplog: pytest.LogCaptureFixture,
) -> None:
    env = KitchenEnv(skill="move-home-to-cube", robot=TOY)
    env.reset(seed=0)
    before = env.arm_q
    with caplog.at_level(logging.INFO, logger="osg_control.environment.joint_reset"):
        assert env.joint_reset() == 0
        assert env.joint_reset() == 0
    said = [r.getMessage() for r in caplog.records if "no null space" in r.getMessage()]
    assert said == ["joint reset skipped: robot 'toy6' has 6 joints, no null space under its "
                    "TCP task"]  # fmt: skip
    np.testing.assert_array_equal(env.arm_q, before)
    assert not env.ik.has_null_space and DiffIKController(PANDA).has_null_space


@pytest.mark.parametrize("backend", ["mink", "pinocchio"])
def test_a_six_joint_ik_converges(backend: str) -> None:
    """Targets from forward kinematics of random in-limit configurations are reached."""
    ik = DiffIKController(TOY, IKConfig(backend=backend))
    lower, upper = np.array(TOY.arm.lower), np.array(TOY.arm.upper)
    rng = np.random.default_rng(5)
    home = np.array(TOY.home_q)
    for _ in range(10):
        goal = np.clip(home + rng.uniform(-0.5, 0.5, 6), lower + 0.05, upper - 0.05)
        pos, rot = ik.tcp_pose(goal)
        solved, converged = solve_ik(ik, home, pos, rot, iterations=300)
        assert converged, goal
        assert np.linalg.norm(ik.tcp_pose(solved)[0] - pos) < 1e-4
    q = home + 0.1
    pos, rot = ik.tcp_pose(q)
    np.testing.assert_array_equal(ik.reset_step(q, pos, rot), q)  # no null space: holds


def test_both_backends_agree_on_a_six_joint_arm() -> None:
    """mink's and Pinocchio's models of the toy arm have the same kinematics, so at the
    TCP's own pose (zero task error) both backends build the same QP (6 x 6, the Hessian's
    diagonal from ``flat[:: n + 1]``); ``test_ik`` holds each to its library's
    ``build_ik`` for six joints."""
    mink_backend = MinkBackend(IKConfig(), TOY)
    pin_backend = PinocchioBackend(IKConfig(backend="pinocchio"), TOY)
    q = np.array(TOY.home_q) + 0.05
    pos, rot = mink_backend.tcp_pose(q)
    pin_pos, pin_rot = pin_backend.tcp_pose(q)
    np.testing.assert_allclose(pos, pin_pos, atol=1e-12)
    np.testing.assert_allclose(rot, pin_rot, atol=1e-12)
    for hard in (False, True):
        a = mink_backend.build_qp(q, pos, rot, hard)
        b = pin_backend.build_qp(q, pos, rot, hard)
        assert a.P.shape == (6, 6)
        np.testing.assert_allclose(a.P, b.P, atol=1e-9)
        np.testing.assert_allclose(a.q, b.q, atol=1e-9)
        np.testing.assert_allclose(np.c_[a.lb, a.ub], np.c_[b.lb, b.ub], atol=1e-12)
    reset = mink_backend.build_qp(q, pos, rot, True).P
    np.testing.assert_array_equal(reset, np.diag(np.diagonal(reset)))
    assert (np.diagonal(reset) > 0).all()


# ------------------------------------------------------------------ validation errors
def _arm(**changes: Any) -> ArmJoints:
    return dataclasses.replace(PANDA.arm, **changes)


@pytest.mark.parametrize(
    "changes,message",
    [
        ({"arm": _arm(velocity=(2.0,) * 6)}, "field 'arm.velocity': has 6 values for 7"),
        ({"arm": _arm(names=("a",) * 7)}, "field 'arm.names': repeats a joint"),
        ({"arm": _arm(effort=(87.0,) * 6 + (0.0,))}, "field 'arm.effort': must be positive"),
        ({"arm": _arm(lower=(3.0,) * 7)}, "field 'arm.lower': joint 'panda_joint1': lower 3.0"),
        ({"home_q": (0.0,) * 7}, "field 'home_q': joint 'panda_joint4': 0.0 is outside"),
        ({"servo": ServoGains((1.0,) * 7, (1.0,) * 5)}, "field 'servo.kv': has 5 values"),
        ({"home_q": (float("nan"),) * 7}, "field 'home_q': must be finite"),
        ({"tcp": dataclasses.replace(PANDA.tcp, frame="")}, "field 'tcp': needs a body"),
        (
            {"tcp": dataclasses.replace(PANDA.tcp, quat=(1.0, 1.0, 0, 0))},
            "field 'tcp.quat': must be a unit",
        ),
        (
            {"gripper": dataclasses.replace(PANDA.gripper, open_position=0.0)},
            "field 'gripper': .* cannot be driven open and shut",
        ),
        (
            {"gripper": dataclasses.replace(PANDA.gripper, joints=("panda_joint7",))},
            "field 'gripper.joints': shares a joint with the arm",
        ),
        ({"sensors": ("encoders", "lidar")}, "field 'sensors': unknown \\['lidar'\\]"),
        ({"control_hz": 0.0}, "field 'control_hz': must be positive"),
    ],
)
def test_an_inconsistent_description_is_refused_with_its_field(
    changes: dict[str, Any], message: str
) -> None:
    with pytest.raises(RobotDescriptionError, match=f"robot 'panda': {message}"):
        dataclasses.replace(PANDA, **changes)


@pytest.mark.parametrize(
    "changes,message",
    [
        (
            {"tcp": dataclasses.replace(PANDA.tcp, frame="no_such_frame")},
            "TCP frame 'no_such_frame' not in its Pinocchio model",
        ),
        (
            {"tcp": dataclasses.replace(PANDA.tcp, body="no_such_body")},
            "TCP body 'no_such_body' not in the model",
        ),
        (
            {"arm": _arm(names=(*PANDA.arm.names[:6], "wrist"))},
            "joint 'wrist' is not a hinge or slide joint of its MuJoCo model",
        ),
        (
            {"gripper": dataclasses.replace(PANDA.gripper, joints=("finger",))},
            "joint 'finger' is not a hinge or slide joint of its MuJoCo model",
        ),
        (
            {"gripper": dataclasses.replace(PANDA.gripper, open_position=0.1)},
            "the gripper cannot be driven open: open_position 0.1 is outside",
        ),
        (
            {"gripper": dataclasses.replace(PANDA.gripper, bodies=("palm",))},
            "gripper bodies \\['palm'\\] not in the model",
        ),
        ({"arm": _arm(upper=(2.8,) * 3 + (-0.0698,) + (2.8973, 3.7525, 2.8973))},
         "MuJoCo position limits .* differ from its description's"),
        ({"arm": _arm(velocity=(2.0,) * 7)}, "Pinocchio velocity limits .* differ"),
    ],
)  # fmt: skip
def test_a_description_that_contradicts_its_models_is_refused(
    changes: dict[str, Any], message: str
) -> None:
    with pytest.raises(RobotDescriptionError, match=f"robot 'panda': {message}"):
        check_models(dataclasses.replace(PANDA, **changes))


def test_a_six_joint_description_of_the_seven_joint_model_is_refused() -> None:
    """Joint counts: a description that leaves a joint of its model out is named."""
    short = dataclasses.replace(TOY, model=PANDA.model)
    with pytest.raises(RobotDescriptionError, match="arm-only MuJoCo model has 7 joints, the"):
        check_models(short)


# ------------------------------------------------------------------ registry and CLI
def test_an_unknown_robot_lists_the_known_ones() -> None:
    known = "known robots: franka-kitchen-panda, panda"
    with pytest.raises(RobotDescriptionError, match=f"unknown robot 'nope'; {known}"):
        registry.get_robot("nope")
    with pytest.raises(RobotDescriptionError, match="unknown robot 'nope'"):
        KitchenEnv(robot="nope")


def test_registered_robots_are_found_by_name(toy_registered: RobotDescription) -> None:
    assert toy_registered is TOY
    assert registry.robot_names() == ["franka-kitchen-panda", "panda", "toy6", "ur5"]
    assert registry.get_robot("panda") is PANDA


def test_a_registered_robot_is_checked_against_its_models(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(registry, "_REGISTERED", dict(registry._REGISTERED))
    broken = dataclasses.replace(TOY, name="broken", model=PANDA.model)
    registry.register_robot(broken)
    with pytest.raises(RobotDescriptionError, match="robot 'broken': its arm-only MuJoCo"):
        registry.get_robot("broken")


def test_osg_robots_json_lists_every_robot(
    toy_registered: RobotDescription, capsys: pytest.CaptureFixture[str]
) -> None:
    assert cli.main(["robots", "--json"]) == 0
    listed = {entry["name"]: entry for entry in json.loads(capsys.readouterr().out)}
    assert sorted(listed) == ["franka-kitchen-panda", "panda", "toy6", "ur5"]
    assert listed["panda"]["joints"] == list(PANDA.arm.names)
    assert listed["panda"]["redundant"] and not listed["toy6"]["redundant"]
    assert listed["toy6"]["gripper"]["max_opening"] == pytest.approx(0.08)
    assert cli.main(["robots"]) == 0
    assert "toy6: the Panda with joint 3 locked" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv,message",
    [
        (
            ["--robot", "nope", "robots"],
            "--robot: unknown robot 'nope'; known robots: franka-kitchen-panda, panda",
        ),
        (["plan", "--goal", "door-open", "--robot=nope"], "--robot: unknown robot 'nope'"),
        (
            ["--domain", "franka-kitchen", "--robot", "panda", "plan", "--goal", "light-on"],
            "--robot: domain 'franka-kitchen' drives its own arm",
        ),
    ],
)
def test_a_bad_robot_option_exits_2(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert cli.main(argv) == 2
    assert message in capsys.readouterr().err


def test_the_robot_option_selects_the_kitchen_robot(toy_registered: RobotDescription) -> None:
    """``osg --robot NAME`` binds the domain's env to the robot while the command runs (its
    own artifacts folder, no shipped defaults of another arm); the registry is as before
    after it."""
    kitchen = get_domain("kitchen")
    seen: list[Any] = []

    def verb(args: Any) -> int:
        domain = get_domain(args.domain)
        seen.extend([domain.robot, domain.ref, domain.defaults_dir])
        seen.append(domain.make_env(skill="move-home-to-cube").robot.name)
        return 0

    parser = cli.build_parser(["plan"])
    args = parser.parse_args(["--robot", "toy6", "plan", "--goal", "door-open"])
    args.func = verb
    with cli.selected_robot(args):
        verb(args)
    assert seen == ["toy6", "kitchen@toy6", None, "toy6"]
    assert get_domain("kitchen") is kitchen and kitchen.robot == "panda"
    assert kitchen.ref == "kitchen" and kitchen.with_robot("panda") is kitchen


def test_a_domain_ref_names_its_robot(toy_registered: RobotDescription) -> None:
    """``get_domain`` takes ``Domain.ref``: ``kitchen@toy6`` is the kitchen around the toy
    arm (how a fresh worker process finds it again); an unknown robot lists the known ones."""
    toy = get_domain("kitchen@toy6")
    assert (toy.name, toy.robot, toy.ref) == ("kitchen", "toy6", "kitchen@toy6")
    assert get_domain(toy.ref) is toy and get_domain("kitchen").robot == "panda"
    with pytest.raises(RobotDescriptionError, match="panda"):
        get_domain("kitchen@no-such-arm")
