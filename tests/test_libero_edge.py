"""An object wider than the open hand (the ``libero`` extra, skipped without it): LIBERO-PRO's
bigger alphabet soup can is pinched across its top edge by the tilted hand, released
into a region above the region's box, and reaches the basket; objects a top-down grasp
closes round keep it."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import scripted_episode, started  # noqa: E402

from osg_control.libero.edge import (  # noqa: E402
    EDGE_CREEP,
    EDGE_CREEP_RATE,
    EDGE_DEPTH,
    EDGE_FIRM,
    EDGE_TILT,
    pinched,
    pinched_last,
)
from osg_control.libero.executor import PlanExecutor  # noqa: E402
from osg_control.libero.facts import region_pose  # noqa: E402
from osg_control.libero.operators import PICKS  # noqa: E402
from osg_control.libero.pick_place import lift  # noqa: E402
from osg_control.libero.plan import plan_holds  # noqa: E402
from osg_control.libero.spots import surface  # noqa: E402

CAN = "bigger_alphabet_soup_1"
BASKET = "red_basket_1_contain_region"


def _picked(policy: PlanExecutor) -> list[str]:
    """The objects the plan picks."""
    return [args[0] for op, args in policy.queue if op in PICKS]


def test_the_wide_can_is_pinched_across_its_top_edge() -> None:
    """The can (9.4 cm round) gets the plan's edge grasp, no other object does: the hand
    tilted ``EDGE_TILT``, its palm out and up, the TCP inside the can's footprint
    ``EDGE_DEPTH / 2`` below its top, the fingers closing in the vertical plane through the
    can's axis."""
    policy, percept = started("libero_10_object", 7)
    ctx = policy.ctx
    assert set(ctx.grasps) == {CAN}
    assert [o for o in _picked(policy) if pinched(ctx, o)] == [CAN]
    point, rotation = ctx.grasps[CAN](percept)
    assert rotation[:, 2] @ [0.0, 0.0, -1.0] == pytest.approx(np.cos(EDGE_TILT), abs=0.01)
    pos = percept.position(CAN)
    low, high = ctx.scene.extents[CAN]
    assert point[2] == pytest.approx(pos[2] + high[2] - EDGE_DEPTH / 2, abs=1e-6)
    out = (point - pos) * [1.0, 1.0, 0.0]
    assert 0.02 < np.linalg.norm(out) < (high[0] - low[0]) / 2  # inside, near the edge
    assert -rotation[:, 2] @ out > 0 and -rotation[:, 2][2] > 0  # the palm out and up
    across = np.cross(out, [0.0, 0.0, 1.0]) / np.linalg.norm(out)  # within 10 deg of it
    assert abs(rotation[:, 1] @ across) < np.sin(np.radians(10.0)) * np.linalg.norm(rotation[:2, 1])


def test_a_pinched_object_is_lifted_slowly_and_no_further_once_slipped() -> None:
    """The pinched can's lift starts with a creep (its target at most ``EDGE_CREEP_RATE``
    above the hand, up to ``EDGE_CREEP``), and the rest of it ends at once when the fingers
    closed nearer than ``EDGE_FIRM``; the cream cheese, held across, lifts at once."""
    policy, percept = started("libero_10_object", 7)
    ctx = policy.ctx
    creeping, rest = lift(ctx, CAN)
    start = percept
    target, _ = creeping.target(percept, start)
    assert target[2] == pytest.approx(percept.tcp[2] + EDGE_CREEP_RATE)
    high = replace(percept, tcp=percept.tcp + [0.0, 0.0, EDGE_CREEP - 0.001])
    assert creeping.target(high, start)[0][2] == pytest.approx(start.tcp[2] + EDGE_CREEP)
    assert rest.until is not None
    assert rest.until(replace(percept, finger_width=EDGE_FIRM - 0.005))
    assert not rest.until(replace(percept, finger_width=EDGE_FIRM + 0.005))
    (cheese_lift,) = lift(ctx, "red_cream_cheese_1")
    assert cheese_lift.until is None


def test_a_pinched_object_is_released_above_the_region() -> None:
    """Into the basket, the can is set down over the region's box (the tilted hand reaches
    past its side), the tomato sauce on its floor as before."""
    policy, percept = started("libero_10_object", 0)
    ctx = policy.ctx
    pos, mat = region_pose(ctx.scene, percept, BASKET)
    half = np.abs(mat @ ctx.scene.regions[BASKET].size)
    assert surface(ctx, percept, BASKET, True, CAN)[2] == pytest.approx(pos[2] + half[2])
    sauce = surface(ctx, percept, BASKET, True, "yellow_tomato_sauce_1")
    assert sauce[2] == pytest.approx(pos[2] - half[2])


def test_the_pinched_object_goes_into_the_region_last() -> None:
    """Task 7's plan carries the can into the basket first; the executor's plan carries the
    cream cheese first (the cheese on the can's top stood outside the basket's region), the
    hand going home between, and still reaches the goal; a plan with no pinched object is
    left as it is."""
    policy, _ = started("libero_10_object", 7)
    queue = policy.queue
    assert _picked(policy) == ["red_cream_cheese_1", CAN]
    assert queue[5] == ("retreat", (BASKET,)) and queue[6] == ("approach", (CAN,))
    assert queue[-2] == ("place-in", (CAN, BASKET))
    assert plan_holds(policy.problem, queue)
    assert pinched_last(policy.ctx, queue) == queue
    assert not plan_holds(policy.problem, queue[:5] + queue[6:])  # not home between
    assert pinched_last(policy.ctx, queue[6:] + queue[:5]) == queue  # the planner's order


@pytest.mark.parametrize(
    "suite, task", [("libero_10", 0), ("libero_10", 7), ("libero_object", 0), ("libero_goal", 5)]
)
def test_objects_a_grasp_closes_round_are_not_pinched(suite: str, task: int) -> None:
    """LIBERO-10's soup can and LIBERO-Object's objects keep their top-down grasps, and so
    does LIBERO-Goal's plate (wider than the hand, too low for the pinch)."""
    policy, _ = started(suite, task)
    assert _picked(policy) and not [o for o in _picked(policy) if pinched(policy.ctx, o)]
    assert not policy.ctx.grasps


@pytest.mark.slow
def test_the_cheese_and_the_can_reach_the_basket(capsys: pytest.CaptureFixture[str]) -> None:
    """``libero_10_object`` task 7, initial state 0: the cream cheese into the basket, then
    the can, picked at its edge at the first try; the episode is won (top-down, every pick
    of the can closed on nothing above it; at the first edge 8 mm clear of the neighbours,
    not the clearest, the fingers slid the can along the table and closed on nothing:
    states 0-9 1 / 10, this one lost)."""
    episode = scripted_episode(capsys, "libero_10_object", 7, 0)
    picks = [line for line in episode["trace"] if f"pick {CAN} " in line]
    assert picks and picks[0].endswith(": ok"), episode["trace"]
    assert episode["success"], episode["trace"]
