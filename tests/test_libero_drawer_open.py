"""The empty hand approaching a drawer the plan opens next turns level for the pull on
its way (``fixtures.drawer_hand``): the open's first leg then has no quarter turn left to
make in place (it took 31-40 of LIBERO-Goal task 3's 300 steps). Needs the libero extra."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import episode_start, started  # noqa: E402

from osg_control.libero.controllers import operator_legs  # noqa: E402
from osg_control.libero.executor import PlanExecutor  # noqa: E402
from osg_control.libero.legs import Context  # noqa: E402

REGION = "white_cabinet_1_bottom_region"


def test_a_drawer_opened_next_is_approached_with_the_hand_the_open_takes() -> None:
    """LIBERO-10 task 3, state 0: its bottom drawer, approached before a close (what its
    plan does), with the start's hand; before an open (``Context.opening``, from the
    plan), with the open's level hand, and the open's legs in free space (the turn, the
    way down in front of the handle) run at the transit pace. The plan executor marks the
    drawers it approaches to open next."""
    start = episode_start("libero_10", 3)
    ctx, percept = start.ctx, start.percept
    executor = PlanExecutor()
    executor.start(start.problem, start.robot, ctx.scene, percept)

    def approached(c: Context) -> np.ndarray:  # the approach's last leg's rotation
        return operator_legs(c, "approach", (REGION,), None)[-1].target(percept, percept)[1]

    assert np.allclose(approached(ctx), ctx.base)
    assert executor.ctx.opening == frozenset()  # the drawer starts open: no open planned
    opening = replace(ctx, opening=frozenset({REGION}))
    level = operator_legs(opening, "open", (REGION, REGION), None)
    assert np.allclose(approached(opening), level[0].target(percept, percept)[1])
    assert not np.allclose(approached(opening), ctx.base)
    assert [leg.transit for leg in level[:3]] == [True, True, False]


def test_the_executor_marks_the_drawer_it_opens_next() -> None:
    """LIBERO-Goal task 0 (open the middle drawer), state 0: its plan approaches the
    middle drawer to open it."""
    executor, _ = started("libero_goal", 0)
    assert executor.ctx.opening == frozenset({"wooden_cabinet_1_middle_region"})
