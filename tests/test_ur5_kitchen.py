"""The UR5 in the home kitchen: its placement reaches every node and skill path
(``tools/ur5_kitchen_reach.py``), and straight-line IK paths do the kitchen's stages in the
kitchen's physics."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from types import ModuleType

import mujoco
import numpy as np
import pytest

from osg_control.control.robot_model import GRIPPER_ACTUATOR, robot_spec
from osg_control.domain.spec import TOP_DOWN_QUAT
from osg_control.kitchen import skills, valve
from osg_control.kitchen.scene import ROBOT_MOUNTS
from osg_control.kitchen.world import WorldState, world_facts
from osg_control.robots import ur5_model
from osg_control.robots.ur5_model import ARM_JOINTS, FINGER_JOINTS, HOME_Q

KITCHEN_BASE = ROBOT_MOUNTS["ur5"]


def _reach_tool() -> ModuleType:
    """``tools/ur5_kitchen_reach.py`` as a module."""
    path = Path(__file__).resolve().parents[1] / "tools" / "ur5_kitchen_reach.py"
    spec = importlib.util.spec_from_file_location("ur5_kitchen_reach", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _reach_report(capsys: pytest.CaptureFixture[str], *arguments: str) -> dict:
    assert _reach_tool().main(["--steps", "200", "--json", *arguments]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.filterwarnings("ignore:Attaching a spec with an empty prefix")
def test_the_kitchen_placement_reaches_every_node_and_skill_path(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """At ``KITCHEN_BASE`` every node is reached TCP down and every skill's straight path is
    reached clear of the furniture and of singularities; at the Panda's base (the origin)
    ``release-handle``'s lift point is out of reach."""
    report = _reach_report(capsys)
    assert all(row["reached"] for row in report["nodes"])
    assert all(row["position_error_m"] < 1e-4 for row in report["nodes"])
    assert all(row["reached"] and not row["touches"] for row in report["skills"])
    assert min(row["min_singular_value"] for row in report["skills"]) > 0.1
    # With the door shut the arm reaching into the cabinet meets the door, and only there.
    assert [r["node"] for r in report["nodes"] if r["touches_door_shut"]] == ["cube-inside"]
    assert not any(row["touches_door_open"] for row in report["nodes"])
    at_origin = _reach_report(capsys, "--base", "0", "0", "0")
    assert [r["skill"] for r in at_origin["skills"] if not r["reached"]] == ["release-handle"]


def test_the_reach_tool_refuses_bad_values(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        _reach_tool().main(["--max-step", "0"])
    assert exit_info.value.code == 2 and "--max-step" in capsys.readouterr().err


@pytest.mark.filterwarnings("ignore:Attaching a spec with an empty prefix")
def test_the_ur5_does_the_kitchen_stages_in_kitchen_physics() -> None:
    """Straight-line IK paths at 2 cm per step through the kitchen's nodes and via points,
    joint targets every 50 ms, the gripper closed and opened at the grasps: in the kitchen's
    physics the fingers close on the handle's 2 cm fin and on the cube, the door opens, the
    cube ends in the cabinet and the valve opens (the kitchen's own facts), with no MuJoCo
    warning."""
    tool = _reach_tool()
    arm = robot_spec(tool.ur5_at(KITCHEN_BASE), with_gripper=False).compile()
    model, _ = tool.kitchen_with_ur5(KITCHEN_BASE)
    data = mujoco.MjData(model)
    arm_qpos = [model.joint(n).qposadr[0] for n in ARM_JOINTS]
    actuators = [model.actuator(n).id for n in ARM_JOINTS]
    gripper = model.actuator(GRIPPER_ACTUATOR).id
    data.qpos[arm_qpos] = data.ctrl[actuators] = HOME_Q
    data.qpos[[model.joint(n).qposadr[0] for n in FINGER_JOINTS]] = ur5_model.FINGER_OPEN
    data.ctrl[gripper] = ur5_model.FINGER_OPEN
    substeps = round(0.05 / model.opt.timestep)

    def go(target: str | tuple[float, float, float], grip: float | None) -> None:
        """Close or open the gripper (``grip``), then move to a node or a point."""
        if grip is not None:
            data.ctrl[gripper] = grip
        point = skills.NODES[target].position if isinstance(target, str) else target
        start = data.qpos[arm_qpos].copy()
        for q in tool.reach_world(arm, point, TOP_DOWN_QUAT, start, 120, 0.02).path:
            data.ctrl[actuators] = q
            mujoco.mj_step(model, data, substeps)

    closed, opened = 0.0, ur5_model.FINGER_OPEN
    steps: list[tuple[str | tuple[float, float, float], float | None]] = [
        ("door-front", None),
        ("handle", None),
        ("handle", closed),
        ("handle-open", None),
        ("handle-open", opened),
        (skills.RELEASE_LIFT, None),
        ("above-cube", None),
        ("cube-grasped", None),
        ("cube-grasped", closed),
        ("cube-lifted", None),
        (skills.WALL_CLEAR, None),
        ("place-front", None),
        ("cube-inside", None),
        ("cube-inside", opened),
        ("cabinet-front", None),
        ("home", None),
        ("above-valve", None),
        ("valve-lever", None),
        *((valve.valve_push_point(angle), None) for angle in valve.VALVE_PUSH_ANGLES),
    ]
    held = []  # the gripper's width after each close: on the handle's fin, on the cube
    for target, grip in steps:
        go(target, grip)
        if grip == closed:
            held.append(sum(data.qpos[model.joint(n).qposadr[0]] for n in FINGER_JOINTS))
    np.testing.assert_allclose(held, [0.02, 2 * skills.CUBE.rest_z], atol=2e-3)
    cube = data.qpos[model.joint("cube_free").qposadr[0] :][:7]
    world = WorldState(
        door_opening=float(data.qpos[model.joint("door_slide").qposadr[0]]),
        valve_angle=float(data.qpos[model.joint("valve_hinge").qposadr[0]]),
        cube_pos=(cube[0], cube[1], cube[2]),
        cube_quat=(cube[3], cube[4], cube[5], cube[6]),
        cube_grasped=False,
        handle_grasped=False,
    )
    assert {"door-open", "cube-in-cabinet", "valve-open"} <= world_facts(world)
    assert data.warning.number.sum() == 0
