"""The wine bottle set on a region's top (the ``libero`` extra, skipped without it): taken
below its top with the palm clear of it, carried with its bottom clear of the target and
raised first, and the episodes won (LIBERO-Goal tasks 2 and 9); other objects and places
keep the grasp they had."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import scripted_episode, started  # noqa: E402

from osg_control.libero.clearance import HAND_BOXES  # noqa: E402
from osg_control.libero.executor import PlanExecutor  # noqa: E402
from osg_control.libero.pick_place import CARRY_CEILING, HELD_CLEARANCE, approach  # noqa: E402
from osg_control.libero.tall import PALM_GAP, neck_grasps  # noqa: E402

BOTTLE = "wine_bottle_1"
RACK = "wine_rack_1_top_region"


@pytest.mark.parametrize("task", [2, 9])
def test_the_bottle_is_grasped_with_the_palm_over_its_top(task: int) -> None:
    """Tasks 2 (the cabinet's top) and 9 (the rack): the plan's grasp of the bottle (set
    before the pick) closes top-down with the palm ``PALM_GAP`` over its top, and so for a
    place into a drawer it is laid down in (``lay``: the 15.8 cm bottle in the top drawer);
    a place of an object whose top the palm clears sets none."""
    policy, percept = started("libero_goal", task)
    ctx = policy.ctx
    assert set(ctx.grasps) == {BOTTLE}
    point, rotation = ctx.grasps[BOTTLE](percept)
    top = percept.position(BOTTLE)[2] + ctx.scene.extents[BOTTLE][1][2]
    assert point[2] + HAND_BOXES[0][2] + PALM_GAP == pytest.approx(top, abs=1e-6)
    assert rotation[:, 2] @ [0.0, 0.0, -1.0] > 0.99
    assert set(neck_grasps(ctx, [("place-in", (BOTTLE, "wooden_cabinet_1_top_region"))])) == {
        BOTTLE
    }
    assert not neck_grasps(ctx, [("place-on", ("cream_cheese_1", RACK))])


class _LearnedPick(PlanExecutor):
    """A plan executor whose ``pick`` a learned skill runs (as ``skills.SkillsExecutor``)."""

    def _learned(self, operator: str) -> bool:
        return operator == "pick"


def test_a_learned_pick_keeps_the_grasp_it_was_recorded_on() -> None:
    """The learned pick was recorded before the neck grasp: it is not given it (task 9
    states 0-2, 0 / 3 with it)."""
    policy, _ = started("libero_goal", 9, _LearnedPick)
    assert not policy.ctx.grasps


def test_the_carry_keeps_the_held_bottom_clear_of_the_target() -> None:
    """Held 13 cm below the hand, the bottle is carried with its bottom at least
    ``HELD_CLEARANCE`` above the rack's anchor, above the carry ceiling (under it the
    bottle's bottom hit the rack and it tipped out of the hand), and the hand rises to
    that height before it moves (on the way to the cabinet it caught on the rack)."""
    policy, percept = started("libero_goal", 9)
    ctx = policy.ctx
    pos, rot = percept.objects[BOTTLE]
    hung = replace(percept, tcp=pos + rot @ np.array([0.0, 0.0, 0.127]))  # at the neck
    rise, move = approach(ctx, RACK, BOTTLE)
    target, _ = move.target(hung, hung)
    bottom = target[2] - 0.127 + ctx.scene.extents[BOTTLE][0][2]
    assert bottom >= ctx.scene.regions[RACK].pos[2] + HELD_CLEARANCE - 1e-6
    assert target[2] > ctx.home_z + CARRY_CEILING
    up, _ = rise.target(hung, hung)
    assert np.allclose(up, [*hung.tcp[:2], target[2]])


@pytest.mark.slow
@pytest.mark.parametrize("task", [2, 9])
def test_scripted_plan_sets_the_bottle_on_its_target(capsys, task: int) -> None:
    """LIBERO-Goal tasks 2 and 9, initial state 1: grasped near its bottom the palm came
    down on the bottle's neck; every pick failed and the episodes ran out of their 300
    steps. Now one plan, nothing failed, within 200 steps."""
    episode = scripted_episode(capsys, "libero_goal", task, 1)
    assert episode["success"] and episode["steps"] < 200, episode["trace"]
    assert not any("FAILED" in line for line in episode["trace"]), episode["trace"]
