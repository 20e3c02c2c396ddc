"""A place on a stove whose knob the goal still turns (the ``libero`` extra, skipped
without it): set down off the centre, the pot keeps out of the turning hand's sweep as far
as the other objects let it; a clear centre is taken as before."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from osg_control.libero.clearance import footprint  # noqa: E402
from osg_control.libero.drive import JointTargetDriver  # noqa: E402
from osg_control.libero.env import LiberoEnv  # noqa: E402
from osg_control.libero.facts import region_pose  # noqa: E402
from osg_control.libero.legs import Context  # noqa: E402
from osg_control.libero.perception import LiberoPercept, LiberoPerception  # noqa: E402
from osg_control.libero.robot import mounted_panda  # noqa: E402
from osg_control.libero.spots import _knob_sweeps, surface  # noqa: E402

STOVE = "flat_stove_1_cook_region"
POT = "moka_pot_1"


def _scene(suite: str, task: int) -> tuple[LiberoPercept, Context, Context]:
    """The first percept of initial state 0 and two contexts: one with the task's goal
    (the stove still to turn on), one without its ``turnon``."""
    env = LiberoEnv(suite, task)
    try:
        obs = env.reset(0)
        scene, percept = LiberoPerception(env).reset(obs, 0)
        robot = mounted_panda(env.sim)
        driver = JointTargetDriver(robot)
        ctx = Context.at_start(scene, driver, robot, percept, env.problem)
    finally:
        env.close()
    assert any(a.predicate == "turnon" for a in ctx.goal)
    return percept, ctx, replace(ctx, goal=tuple(a for a in ctx.goal if a.predicate != "turnon"))


def _set_down(ctx: Context, percept: LiberoPercept) -> np.ndarray:
    """Where the pot is set down on the stove (its origin's xy; ``spots.surface``, the first
    choice, which the arm reaches here)."""
    return surface(ctx, percept, STOVE, False, POT)[:2]


def _knob_gap(ctx: Context, percept: LiberoPercept, spot: np.ndarray) -> float:
    """How far the pot set down at ``spot`` stands from the knob's sweep (negative: in it)."""
    pos, rot = percept.objects[POT]
    moved = replace(percept, objects={**percept.objects, POT: (np.r_[spot, pos[2]], rot)})
    (sweep,) = _knob_sweeps(ctx, percept)
    box = footprint(ctx, moved, POT)
    return float(np.max(np.maximum(sweep[0] - box[1], box[0] - sweep[1])))


def test_an_off_centre_spot_keeps_out_of_the_knobs_sweep() -> None:
    """LIBERO-PRO's swapped kitchen (``libero_10_swap`` task 2): the frying pan's handle
    reaches over the stove's centre; with the turn still to come the pot is set down
    farther from the knob than with it done (it was set down where the turn pushed it
    off the stove)."""
    percept, ctx, turned = _scene("libero_10_swap", 2)
    spot, before = _set_down(ctx, percept), _set_down(turned, percept)
    assert not np.allclose(before, region_pose(ctx.scene, percept, STOVE)[0][:2])
    assert _knob_gap(ctx, percept, spot) > _knob_gap(ctx, percept, before) + 0.02


def test_a_clear_centre_is_taken_with_a_turn_to_come() -> None:
    """LIBERO-10 task 2: nothing near the stove, the pot goes to its centre either way."""
    percept, ctx, turned = _scene("libero_10", 2)
    centre = region_pose(ctx.scene, percept, STOVE)[0][:2]
    assert np.allclose(_set_down(ctx, percept), centre)
    assert np.allclose(_set_down(turned, percept), centre)
