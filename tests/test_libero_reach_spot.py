"""A set-down spot beyond the arm's reach (the ``libero`` extra, skipped without it):
LIBERO-PRO's swapped kitchen (``libero_10_swap`` task 8) puts the stove's cook region
0.87 m out, where the top-down hand reaches only its near edge; the first moka pot goes to
the part the arm reaches and leaves the second room there, and the second is turned a
quarter turn to fit beside it. LIBERO-10's stove, within reach, keeps the first choice."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import scripted_episode  # noqa: E402

from osg_control.libero.env import LiberoEnv  # noqa: E402
from osg_control.libero.executor import PlanExecutor  # noqa: E402
from osg_control.libero.facts import region_pose  # noqa: E402
from osg_control.libero.legs import Context  # noqa: E402
from osg_control.libero.perception import LiberoPercept, LiberoPerception  # noqa: E402
from osg_control.libero.pick_place import place  # noqa: E402
from osg_control.libero.robot import mounted_panda  # noqa: E402
from osg_control.libero.spots import EDGE_MARGIN, reaches, set_down, surface  # noqa: E402

STOVE = "flat_stove_1_cook_region"
POT = "moka_pot_1"


def _at_place(suite: str, task: int, state: int) -> tuple[Context, LiberoPercept]:
    """The plan executor run on ``task``'s initial ``state`` up to the first pot's
    place on the stove: its context and the percept it places from."""
    env = LiberoEnv(suite, task)
    try:
        perception = LiberoPerception(env)
        scene, percept = perception.reset(env.reset(state), state)
        policy = PlanExecutor()
        policy.start(env.problem, mounted_panda(env.sim), scene, percept)
        for _ in range(200):
            if policy.current == ("place-on", (POT, STOVE)):
                return policy.ctx, percept
            percept = perception.percept(env.step(np.asarray(policy.act(percept))))
    finally:
        env.close()
    raise AssertionError("the plan did not come to place the pot on the stove")


def test_a_spot_out_of_reach_moves_into_the_reached_part_of_the_region() -> None:
    """Swapped kitchen, state 1: the first choice (the far end of the row both pots fill)
    is beyond the IK's reach; the spot taken is reached, lies on the region (less
    ``EDGE_MARGIN``) nearer the arm's base, and the hand comes over it at the carrying
    height as near as the arm gets (2-3 cm short of the spot's own point up there)."""
    ctx, percept = _at_place("libero_10_swap", 8, 1)
    first = surface(ctx, percept, STOVE, False, POT)
    assert not reaches(ctx, percept, POT, first, 0.0)
    chosen = set_down(ctx, percept, STOVE, False, POT)
    assert chosen.turned is None  # the first pot fits unturned, the second gets the turn
    assert reaches(ctx, percept, POT, chosen.point, 0.0)
    centre, mat = region_pose(ctx.scene, percept, STOVE)
    half = np.abs(mat @ ctx.scene.regions[STOVE].size)[:2]
    assert np.all(np.abs(chosen.point[:2] - centre[:2]) <= half - EDGE_MARGIN + 1e-9)
    base = ctx.base_xy[:2]
    assert np.linalg.norm(chosen.point[:2] - base) < np.linalg.norm(first[:2] - base) - 0.05
    assert chosen.over is not None and chosen.over[2] == pytest.approx(percept.tcp[2], abs=0.01)


def test_a_stove_within_reach_keeps_the_first_choice() -> None:
    """LIBERO-10 task 8, state 0: the stove is reached, the pot goes where ``surface``
    puts it, unturned, and the place's turning legs do nothing (they end where they
    start)."""
    ctx, percept = _at_place("libero_10", 8, 0)
    chosen = set_down(ctx, percept, STOVE, False, POT)
    assert np.array_equal(chosen.point, surface(ctx, percept, STOVE, False, POT))
    assert chosen.turned is None and chosen.before is None and chosen.over is None
    legs = place(ctx, POT, STOVE, False)
    for leg in (legs[0], legs[-1]):
        tcp, rotation = leg.target(percept, percept)
        assert rotation is None and np.array_equal(tcp, percept.tcp)


@pytest.mark.slow
def test_both_pots_stand_on_the_far_stove(capsys) -> None:
    """Swapped kitchen, state 1, within its 520 steps: both pots on the stove (one turned
    a quarter turn beside the other) and the stove on; no operator failed."""
    episode = scripted_episode(capsys, "libero_10_swap", 8, 1)
    assert episode["success"], episode["trace"]
    assert not any("FAILED" in line for line in episode["trace"])
