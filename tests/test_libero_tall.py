"""The wine bottle set on the rack (the ``libero`` extra, skipped without it): taken below
its top with the palm clear of it when the plan sets it on a tilted region, carried with
its bottom clear of the target, and the episode won; a level top keeps the low grasp."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from osg_control import cli  # noqa: E402
from osg_control.libero.clearance import HAND_BOXES  # noqa: E402
from osg_control.libero.env import LiberoEnv  # noqa: E402
from osg_control.libero.executor import PlanExecutor  # noqa: E402
from osg_control.libero.perception import LiberoPercept, LiberoPerception  # noqa: E402
from osg_control.libero.pick_place import CARRY_CEILING, HELD_CLEARANCE, approach  # noqa: E402
from osg_control.libero.robot import mounted_panda  # noqa: E402
from osg_control.libero.tall import PALM_GAP, neck_grasps, tilted  # noqa: E402

BOTTLE = "wine_bottle_1"
RACK = "wine_rack_1_top_region"
CABINET_TOP = "wooden_cabinet_1_top_side"


def _started(task: int) -> tuple[PlanExecutor, LiberoPercept]:
    """The plan executor started on LIBERO-Goal ``task``, initial state 0, and its percept."""
    env = LiberoEnv("libero_goal", task)
    try:
        obs = env.reset(0)
        scene, percept = LiberoPerception(env).reset(obs, 0)
        policy = PlanExecutor()
        policy.start(env.problem, mounted_panda(env.sim), scene, percept)
    finally:
        env.close()
    return policy, percept


def test_the_bottle_for_the_rack_is_grasped_with_the_palm_over_its_top() -> None:
    """Task 9 (the rack, its slot 62 deg from level): the plan's grasp of the bottle
    (set before the pick) closes with the palm ``PALM_GAP`` over its top; task 2 (the
    cabinet's level top) keeps the top-down grasp near its bottom."""
    policy, percept = _started(9)
    ctx = policy.ctx
    assert tilted(ctx, percept, RACK) and not tilted(ctx, percept, CABINET_TOP)
    assert set(ctx.grasps) == {BOTTLE}
    point, rotation = ctx.grasps[BOTTLE](percept)
    top = percept.position(BOTTLE)[2] + ctx.scene.extents[BOTTLE][1][2]
    assert point[2] + HAND_BOXES[0][2] + PALM_GAP == pytest.approx(top, abs=1e-6)
    assert rotation[:, 2] @ [0.0, 0.0, -1.0] > 0.99  # top-down
    assert not neck_grasps(ctx, percept, [("place-on", (BOTTLE, CABINET_TOP))])
    policy2, _ = _started(2)
    assert not policy2.ctx.grasps


def test_the_carry_keeps_the_held_bottom_clear_of_the_target() -> None:
    """Held 13 cm below the hand, the bottle is carried with its bottom at least
    ``HELD_CLEARANCE`` above the rack's anchor, above the carry ceiling (under it the
    bottom hit the rack and the bottle tipped out of the hand)."""
    policy, percept = _started(9)
    ctx = policy.ctx
    pos, rot = percept.objects[BOTTLE]
    hung = replace(percept, tcp=pos + rot @ np.array([0.0, 0.0, 0.127]))  # held at the neck
    target, _ = approach(ctx, RACK, BOTTLE)[1].target(hung, hung)
    rack_z = ctx.scene.regions[RACK].pos[2]
    bottom = target[2] - 0.127 + ctx.scene.extents[BOTTLE][0][2]
    assert bottom >= rack_z + HELD_CLEARANCE - 1e-6
    assert target[2] > ctx.home_z + CARRY_CEILING


@pytest.mark.slow
def test_scripted_plan_sets_the_bottle_on_the_rack(capsys) -> None:
    """LIBERO-Goal task 9, initial state 1: grasped near its bottom the palm came down on
    the bottle's neck and tipped it; every pick failed and the episode ran out of its 300
    steps. Now one plan, nothing failed, well within them."""
    argv = ["--domain", "libero", "evaluate", "benchmark", "--suite", "libero_goal", "--task",
            "9", "--init-states", "1:2", "--policy", "scripted-plan", "--json"]  # fmt: skip
    assert cli.main(argv) == 0
    (episode,) = json.loads(capsys.readouterr().out)["episode_log"]
    assert episode["success"] and episode["steps"] < 150, episode["trace"]
    assert not any("FAILED" in line for line in episode["trace"]), episode["trace"]
