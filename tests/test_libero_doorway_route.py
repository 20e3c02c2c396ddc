"""Carrying an object to a doorway whose fixture stands in the way (the ``libero`` extra,
skipped without it): LIBERO-PRO's ``libero_10_swap`` puts the microwave between the mug
and the microwave's own doorway; the mug then goes over the microwave's body, not through
it. Where the way is clear (LIBERO-10) the approach is the straight one it was. A push
whose hand arrives without the object moving on aims further in. The object goes in
across the middle of the opening the microwave's walls leave, not of its region's box."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import episode_start  # noqa: E402

from osg_control.libero.insert import (  # noqa: E402
    INSERT_LIFT,
    PUSH_DEEPEST,
    ROOF_CLEARANCE,
    approach,
    crosses,
    doorway,
    entry_lift,
    insert,
    opening,
)

REGION = "microwave_1_heating_region"


def test_crosses_tests_the_way_against_the_box() -> None:
    low, high = np.array([0.0, 0.0]), np.array([1.0, 1.0])
    assert crosses(np.array([-1.0, 0.5]), np.array([2.0, 0.5]), low, high)
    assert not crosses(np.array([-1.0, 1.5]), np.array([2.0, 1.5]), low, high)
    assert not crosses(np.array([-1.0, 0.5]), np.array([-0.1, 0.5]), low, high)


def test_opening_cuts_each_wall_off_the_side_it_reaches_in_least() -> None:
    """A wall reaching 3 cm into the box's +x side and one 1 cm into its floor are cut off
    those sides; a wall clear of the box leaves it as it is."""
    low, high = np.array([0.0, 0.0, 0.0]), np.array([0.2, 0.1, 0.1])
    side = (np.array([0.17, -0.05, -0.05]), np.array([0.3, 0.15, 0.15]))
    floor = (np.array([-0.05, -0.05, -0.05]), np.array([0.25, 0.15, 0.01]))
    clear = (np.array([0.3, 0.0, 0.0]), np.array([0.4, 0.1, 0.1]))
    cut_low, cut_high = opening(low, high, [side, floor, clear])
    assert np.allclose(cut_low, [0.0, 0.0, 0.01]) and np.allclose(cut_high, [0.17, 0.1, 0.1])
    same_low, same_high = opening(low, high, [clear])
    assert np.allclose(same_low, low) and np.allclose(same_high, high)


@pytest.mark.parametrize("suite", ["libero_10", "libero_10_swap"])
def test_the_doorway_is_centred_on_the_opening_between_the_walls(suite: str) -> None:
    """The heating region's box reaches 5.6 cm into the wall beside the microwave's
    doorway: across the doorway the white-and-yellow mug (10.6 cm, its handle out) goes in
    at the middle of the opening the scene's walls leave, clearing the side walls by 4 cm
    (on the region's centre it met that wall, ``libero_10_swap`` task 9 states 0-3)."""
    scene, _, _ = _first(suite)
    way = doorway(scene, REGION)
    n, across = way.normal, np.cross([0.0, 0.0, 1.0], way.normal)
    box = scene.regions[REGION]
    front = float(n @ box.pos) + float(np.abs(box.mat @ box.size) @ np.abs(n))
    centre, half = float(across @ way.centre), float(scene.extents["white_yellow_mug_1"][1][1])
    assert abs(float(across @ box.pos) - centre) > 0.02  # the region's box is off-centre
    sides = [
        sorted((float(across @ lo), float(across @ hi)))
        for lo, hi in scene.walls["microwave_1"]
        if lo[2] < box.pos[2] < hi[2] and min(n @ lo, n @ hi) < front < max(n @ lo, n @ hi)
    ]
    assert len(sides) == 2  # the two sides of the doorway
    gaps = [max(low - (centre + half), (centre - half) - high) for low, high in sides]
    assert min(gaps) > 0.03


def _first(suite: str):
    start = episode_start(suite, 9)
    return start.ctx.scene, start.percept, start.ctx


def test_a_push_that_arrives_aims_further_in() -> None:
    """The hand at its push target with the object where it was: each step the target moves
    in along the doorway's normal, up to ``PUSH_DEEPEST``; a hand short of it keeps it."""
    scene, percept, ctx = _first("libero_10_swap")
    n = doorway(scene, REGION).normal
    push = insert(ctx, "white_yellow_mug_1", REGION)[5]
    outside = replace(percept, tcp=percept.position("white_yellow_mug_1") + n)
    first, _ = push.target(outside, percept)
    short = replace(percept, tcp=first + 0.02 * n)
    assert np.allclose(push.target(short, percept)[0], first)
    depths = []
    for _ in range(40):
        arrived = replace(percept, tcp=push.target(outside, percept)[0])
        depths.append(float(n @ push.target(arrived, percept)[0]))
    assert depths[0] < n @ first and all(np.diff(depths) <= 0)
    assert n @ first - depths[-1] == pytest.approx(PUSH_DEEPEST, abs=1e-9)


@pytest.mark.parametrize(("suite", "routed"), [("libero_10", False), ("libero_10_swap", True)])
def test_the_mug_goes_over_the_microwave_only_where_it_is_in_the_way(
    suite: str, routed: bool
) -> None:
    scene, percept, ctx = _first(suite)
    low, high = scene.housings["microwave_1"]
    centre = scene.regions[REGION].pos
    assert np.all(low < centre) and np.all(centre < high)  # the body round its heating region
    mug = "white_yellow_mug_1"
    _turn, rise, over, *_ = approach(ctx, REGION, mug)
    assert rise.until is not None and rise.until(percept) is (not routed)
    if routed:
        target, _ = rise.target(percept, percept)
        top = high[2] + 0.05  # TRANSIT_CLEARANCE over the body's top
        carried_bottom = target[2] - percept.tcp[2] + percept.position(mug)[2]
        assert carried_bottom + scene.extents[mug][0][2] == pytest.approx(top, abs=1e-9)


def test_a_mug_too_tall_for_the_usual_lift_goes_in_lower() -> None:
    """LIBERO-PRO ``_object`` task 9's red mug (13.3 cm) goes in with its top
    ``ROOF_CLEARANCE`` under the opening's top, its bottom still over the opening's floor
    (carried ``INSERT_LIFT`` up, it met the roof's front edge); LIBERO-10's porcelain mug
    goes in ``INSERT_LIFT`` up, as before."""
    start = episode_start("libero_10_object", 9)
    way = doorway(start.ctx.scene, REGION)
    assert way is not None
    mug = "red_coffee_mug_1"
    low, high = start.ctx.scene.extents[mug]
    lift = entry_lift(start.ctx, mug, way)
    assert lift < INSERT_LIFT
    assert way.floor + lift + float(high[2] - low[2]) == pytest.approx(way.roof - ROOF_CLEARANCE)
    floor_top = max(float(w[1][2]) for w in start.ctx.scene.walls["microwave_1"] if w[1][2] < 1.0)
    assert way.floor + lift > floor_top
    ten = episode_start("libero_10", 9)
    ten_way = doorway(ten.ctx.scene, REGION)
    assert ten_way is not None
    assert entry_lift(ten.ctx, "porcelain_mug_1", ten_way) == INSERT_LIFT
