"""Where a place on a region's top sets an object down (``pick_place.free_spot``,
``shared_spot``; ``clearance.upright_rotation``): pure geometry, no simulator."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.clearance import upright_rotation
from osg_control.libero.pick_place import CLEARANCE, free_spot, shared_spot

CENTRE = np.array([-0.05, -0.2])
HALF = np.array([0.075, 0.075])  # a stove's cook region: 15 x 15 cm
POT = np.array([[-0.041, -0.056], [0.041, 0.091]])  # a moka pot about its origin: 8 x 15 cm
BASE = np.array([-0.66, 0.0])  # the arm's base, at -x


def test_a_lone_object_goes_to_the_centre() -> None:
    """Nothing else there and nothing to come: the region's centre."""
    np.testing.assert_allclose(free_spot(POT, [], CENTRE, HALF), CENTRE)


def test_the_first_of_two_takes_the_far_half_across_the_long_side() -> None:
    """The goal puts a second pot there after this one: the region is cut into two slots
    across x (the pots are narrower along x: 16 cm of 15 leaves more room than 30 of 15),
    and the first takes the slot centre farther from the arm's base, a quarter of the
    region off its centre; the mirror slot is left for the second."""
    spot = shared_spot(POT, [], CENTRE, HALF, [POT], BASE)
    np.testing.assert_allclose(spot, CENTRE + [HALF[0] / 2, 0.0])
    assert np.allclose(free_spot(POT, [], CENTRE, HALF, [POT], BASE), spot)


def test_the_slots_run_along_the_axis_with_more_room() -> None:
    """Objects long along x share the region along y."""
    long_x = POT[:, ::-1]
    spot = shared_spot(long_x, [], CENTRE, HALF, [long_x], np.array([0.0, -1.0]))
    np.testing.assert_allclose(spot, CENTRE + [0.0, HALF[1] / 2])


def test_a_slot_already_taken_is_left() -> None:
    """Something already stands on the far slot: the near one, though nearer the base."""
    far = CENTRE + [HALF[0] / 2, 0.0]
    taken = POT + far
    spot = shared_spot(POT, [taken], CENTRE, HALF, [POT], BASE)
    np.testing.assert_allclose(spot, CENTRE - [HALF[0] / 2, 0.0])


def test_three_objects_cut_the_region_in_three() -> None:
    """Two still to come: three slots, the first at the far third's centre."""
    small = POT / 3
    spot = shared_spot(small, [], CENTRE, HALF, [small, small], BASE)
    np.testing.assert_allclose(spot, CENTRE + [2 * HALF[0] / 3, 0.0], atol=1e-12)


def test_the_last_one_takes_the_clearest_spot() -> None:
    """Nothing left to come and the first pot at the far slot: the second stands
    ``CLEARANCE`` clear of it, inside the region, on the near side."""
    first = POT + CENTRE + [HALF[0] / 2, 0.0]
    spot = free_spot(POT, [first], CENTRE, HALF)
    box = POT + spot
    gap = float(np.max(np.maximum(first[0] - box[1], box[0] - first[1])))
    assert spot[0] < CENTRE[0] and gap >= CLEARANCE
    assert np.all(np.abs(spot - CENTRE) <= HALF)


def test_upright_keeps_the_heading_and_drops_the_tilt() -> None:
    """A pot carried tilted 50 deg by its handle, heading 120 deg: upright it is the turn
    of 120 deg about the vertical; a tilt about its x axis keeps the heading too."""
    heading = Rotation.from_euler("z", 120, degrees=True)
    for tilt in ("y", "x"):
        rot = (heading * Rotation.from_euler(tilt, 50, degrees=True)).as_matrix()
        np.testing.assert_allclose(upright_rotation(rot), heading.as_matrix(), atol=1e-12)
