"""The UR5 as a registered robot in the home kitchen: listed by ``osg robots``, mounted where
the kitchen declares, refused where it cannot reach the kitchen's skills, and a scripted
episode run through ``osg --robot ur5``."""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np
import pytest

from osg_control import cli
from osg_control.control.robot_model import workspace
from osg_control.domain.reach import UnreachableError, unreachable
from osg_control.domain.registry import domain_override, get_domain
from osg_control.errors import EnvOptionError
from osg_control.kitchen.options import check_cube_position
from osg_control.kitchen.scene import ROBOT_MOUNTS
from osg_control.paths import PACKAGE_DIR
from osg_control.robots.registry import get_robot


def test_osg_robots_json_lists_the_panda_and_the_ur5(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["robots", "--json"]) == 0
    listed = {entry["name"]: entry for entry in json.loads(capsys.readouterr().out)}
    assert {"panda", "ur5"} <= set(listed)
    ur5 = listed["ur5"]
    assert len(ur5["joints"]) == 6 and not ur5["redundant"]
    assert ur5["gripper"]["max_opening"] == pytest.approx(0.085)
    assert ur5["mount"] == {"position": [0.0, 0.0, 0.0], "quat": [1.0, 0.0, 0.0, 0.0]}


def test_the_kitchen_mounts_the_ur5_and_its_home_is_the_home_node() -> None:
    """``with_robot`` builds the env around the UR5 at the kitchen's mount: the home key
    puts the TCP on the home node, in scene coordinates."""
    kitchen = get_domain("kitchen").with_robot("ur5")
    assert (kitchen.robot, kitchen.ref) == ("ur5", "kitchen@ur5")
    env = kitchen.make_env(skill="move-home-to-cube")
    assert env.robot.name == "ur5" and env.robot.mount == ROBOT_MOUNTS["ur5"]
    env.reset(seed=0)
    mujoco.mj_resetDataKeyframe(env.model, env.data, env.model.key("arm-home").id)
    mujoco.mj_forward(env.model, env.data)
    home = kitchen.nodes["home"].position
    np.testing.assert_allclose(env.data.site(env.robot.tcp.site).xpos, home, atol=1e-3)
    env.close()


def test_a_robot_out_of_reach_is_refused_before_any_episode() -> None:
    """At the origin the UR5 misses release-handle's lift point: ``with_robot`` says so,
    naming the skill; the Panda, the kitchen's own, reaches everything."""
    kitchen = get_domain("kitchen")
    with pytest.raises(UnreachableError, match=r"'ur5'.*'release-handle' waypoint 1"):
        replace(kitchen, mounts={}).with_robot("ur5")
    assert unreachable(kitchen, get_robot("panda")) == []


@pytest.mark.usefixtures("no_physics")
def test_osg_robot_out_of_reach_exits_1_naming_it_before_any_episode(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The same through the command line: ``osg --robot ur5 run`` on a kitchen that mounts
    it at the origin exits 1 naming the waypoint it misses, no physics step run."""
    unmounted = replace(get_domain("kitchen"), mounts={})
    with domain_override(unmounted):
        code = cli.main(["--robot", "ur5", "run", "--goal", "door-open", "--episodes", "1"])
    assert code == 1
    assert re.search(
        r"robot 'ur5' .*cannot reach.*'release-handle' waypoint 1", capsys.readouterr().err
    )


def test_the_cube_option_is_checked_against_the_robots_workspace() -> None:
    """The workspace sphere comes from the arm's kinematics at its mount."""
    centre, radius = workspace(replace(get_robot("ur5"), mount=ROBOT_MOUNTS["ur5"]))
    assert centre == pytest.approx((0.10, 0.15, 0.089159))
    assert 0.85 < radius < 1.5  # the links' lengths: an upper bound on the UR5's 0.85 m
    with pytest.raises(EnvOptionError, match="out of the arm's reach"):
        check_cube_position(np.array([1.6, 0.15, 0.0225]), (centre, radius))


def test_osg_robot_ur5_collects_scripted_episodes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``osg --robot ur5 collect``: the kitchen env built around the UR5 runs Algorithm 1's
    scripted policy and writes its data set."""
    argv = ["--robot", "ur5", "collect", "--skill", "move-home-to-cube", "--episodes", "2"]
    argv += ["--workers", "1", "--seed", "0", "--out", str(tmp_path), "--json"]
    assert cli.main(argv) == 0
    (row,) = json.loads(capsys.readouterr().out)
    assert row["skill"] == "move-home-to-cube" and row["episodes"] == 2
    assert row["steps"] > 0 and row["success_rate"] in (0.0, 0.5, 1.0)
    assert (tmp_path / "move-home-to-cube.h5").is_file()


def test_the_shipped_ur5_defaults_run_kitchen_tasks(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``osg --robot ur5 evaluate tasks`` runs from ``kitchen/defaults-ur5`` (skills,
    classifier and plan costs of the UR5) with nothing but the checkout."""
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path))
    kitchen = get_domain("kitchen").with_robot("ur5")
    assert kitchen.defaults_dir == PACKAGE_DIR / "kitchen" / "defaults-ur5"
    argv = ["--robot", "ur5", "evaluate", "tasks", "--task", "pick-up", "open-door"]
    argv += ["--perception", "robot", "--episodes", "1", "--replans", "2", "--workers", "1"]
    assert cli.main([*argv, "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["models"]["source"] == "shipped defaults"
    assert report["models"]["directory"] == str(kitchen.defaults_dir)
    assert report["tasks"] == ["pick-up", "open-door"]
    (averages,) = report["averages"]  # one replanning budget
    assert len(averages) == 2 and all(0.0 <= rate <= 1.0 for rate in averages)
