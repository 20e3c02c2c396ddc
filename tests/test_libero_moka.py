"""LIBERO-10's two moka pots on one stove (task 8; the ``libero`` extra, skipped without
it): each pot grasped over its centre by the lid's knob, so that it hangs level, and the
first set down at one end of the row the goal fills, leaving the second room."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import scripted_episode  # noqa: E402

from osg_control.libero.clearance import HAND_BOXES, footprint  # noqa: E402
from osg_control.libero.drive import JointTargetDriver  # noqa: E402
from osg_control.libero.env import LiberoEnv  # noqa: E402
from osg_control.libero.facts import region_pose  # noqa: E402
from osg_control.libero.grasp import TOP_GAP, grip, slab  # noqa: E402
from osg_control.libero.legs import Context  # noqa: E402
from osg_control.libero.perception import LiberoPercept, LiberoPerception  # noqa: E402
from osg_control.libero.robot import mounted_panda  # noqa: E402
from osg_control.libero.spots import CLEARANCE, surface  # noqa: E402

STOVE = "flat_stove_1_cook_region"
POTS = ("moka_pot_1", "moka_pot_2")


@pytest.fixture(scope="module")
def kitchen():
    """LIBERO-10 task 8 at initial state 0: the env, its first percept and a context that
    knows the goal."""
    env = LiberoEnv("libero_10", 8)
    obs = env.reset(0)
    scene, percept = LiberoPerception(env).reset(obs, 0)
    robot = mounted_panda(env.sim)
    driver = JointTargetDriver(robot)
    ctx = Context.at_start(scene, driver, robot, percept, env.problem)
    yield env, percept, ctx
    env.close()


def test_a_moka_pot_is_grasped_by_its_lid_knob(kitchen) -> None:
    """The pot is wider than the open hand at its centre: its preferred grasp is over its
    centre on the knob, the fingers' lower faces ``TOP_GAP`` over the rest of the pot (its
    handle, taken before, hung it 35-57 deg tilted)."""
    _, _, ctx = kitchen
    g = grip(ctx, "moka_pot_1")
    assert g.axis is not None
    tops = sorted({float(hi[2]) for _, hi in slab(ctx, "moka_pot_1", g.axis, 0.0)}, reverse=True)
    assert np.allclose(g.point[:2], 0.0, atol=0.005)
    assert g.point[2] + HAND_BOXES[-1][2] == pytest.approx(tops[1] + TOP_GAP)
    assert tops[0] > g.point[2]  # the pads close on the knob


def _set_down(ctx: Context, percept: LiberoPercept, pot: str) -> np.ndarray:
    """Where ``place`` sets ``pot`` down on the stove: its origin's xy (``spots.surface``:
    the arm reaches the whole stove here)."""
    return surface(ctx, percept, STOVE, False, pot)[:2]


def _moved(percept: LiberoPercept, obj: str, position: np.ndarray) -> LiberoPercept:
    """The percept with ``obj`` at ``position``, turned as it was."""
    return replace(percept, objects={**percept.objects, obj: (position, percept.objects[obj][1])})


def test_the_first_pot_leaves_the_second_room(kitchen) -> None:
    """The first pot goes to one end of the row both pots fill on the stove; the second,
    set down after it, stands ``CLEARANCE`` clear of it, both origins on the region."""
    _, percept, ctx = kitchen
    centre, mat = region_pose(ctx.scene, percept, STOVE)
    half = np.abs(mat @ ctx.scene.regions[STOVE].size)[:2]
    first = _set_down(ctx, percept, POTS[0])
    moved = _moved(percept, POTS[0], np.r_[first, percept.position(POTS[0])[2]])
    second = _set_down(ctx, moved, POTS[1])
    both = _moved(moved, POTS[1], np.r_[second, percept.position(POTS[1])[2]])
    a, b = (footprint(ctx, both, pot) for pot in POTS)
    assert float(np.max(np.maximum(a[0] - b[1], b[0] - a[1]))) >= CLEARANCE - 1e-6
    for spot in (first, second):
        assert np.all(np.abs(spot[:2] - centre[:2]) < half)
    assert np.linalg.norm(first[:2] - centre[:2]) > 0.03  # not at the centre


@pytest.mark.slow
def test_scripted_plan_puts_both_moka_pots_on_the_stove(capsys) -> None:
    """LIBERO-10 task 8, initial state 0, within 520 steps: both pots carried level and
    set down side by side, no operator failed."""
    episode = scripted_episode(capsys, "libero_10", 8, 0)
    assert episode["success"], episode["trace"]
    assert not any("FAILED" in line for line in episode["trace"])
