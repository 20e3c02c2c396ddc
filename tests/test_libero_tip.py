"""An object another lands on in the same region, let go on its side (the ``libero`` extra,
skipped without it): LIBERO-PRO's ``libero_10_object`` task 0 puts the 9.4 cm soup can and
the tomato sauce into a basket where they do not stand side by side; the can, let go above
the basket last, stood on the standing sauce with its origin above the region's box."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from libero_start import episode_start, scripted_episode  # noqa: E402

from osg_control.libero.clearance import posed_corners  # noqa: E402
from osg_control.libero.facts import region_pose  # noqa: E402
from osg_control.libero.tip import TIP_ANGLE, TIP_DROP, release, tipped, tips_over  # noqa: E402

CAN, SAUCE = "bigger_alphabet_soup_1", "yellow_tomato_sauce_1"
BASKET = "red_basket_1_contain_region"


def _places(*objects: str, region: str = BASKET) -> list[tuple[str, tuple[str, ...]]]:
    return [("place-in", (obj, region)) for obj in objects]


def test_the_sauce_under_the_bigger_can_lies_down_and_nothing_else_does() -> None:
    """The sauce the can lands on goes in lying; the can itself (pinched at its edge) never
    does, nor the sauce when nothing comes after it; LIBERO-10's own soup can on the
    standing sauce stands inside the box, and the cream cheese box is lower than wide."""
    start = episode_start("libero_10_object", 0, 40)
    ctx, percept = start.ctx, start.percept
    assert tips_over(ctx, percept, SAUCE, BASKET, CAN)
    assert not tips_over(ctx, percept, CAN, BASKET, SAUCE)
    assert tipped(ctx, percept, _places(SAUCE, CAN)) == {SAUCE}
    assert tipped(ctx, percept, _places(CAN, SAUCE)) == frozenset()
    assert tipped(ctx, percept, _places(SAUCE)) == frozenset()
    plain = episode_start("libero_10", 0, 0)
    steps = _places("tomato_sauce_1", "alphabet_soup_1", region="basket_1_contain_region")
    assert tipped(plain.ctx, plain.percept, steps) == frozenset()
    assert tipped(plain.ctx, plain.percept, steps[::-1]) == frozenset()
    cheese = episode_start("libero_10_object", 7, 40)
    assert tipped(cheese.ctx, cheese.percept, _places("red_cream_cheese_1", CAN)) == frozenset()


def test_the_release_turns_the_sauce_toward_the_base_just_above_the_box() -> None:
    """With the sauce held under the hand, the release's hand point keeps the sauce's
    lowest corner ``TIP_DROP`` above the region's box from upright to turned (and no
    lower at any angle between), the turn is ``TIP_ANGLE`` about the fingers' axis with
    the hand's approach leaning toward the arm's base, and the last leg turns it back."""
    start = episode_start("libero_10_object", 0, 40)
    ctx = start.ctx
    held = replace(start.percept, tcp=start.percept.position(SAUCE) + np.array([0.0, 0.0, 0.01]))
    pos, mat = region_pose(ctx.scene, held, BASKET)
    top = float(pos[2] + np.abs(mat[2]) @ ctx.scene.regions[BASKET].size)
    spot = np.r_[pos[:2], top + 0.2]
    lower, turn, _, _, back = release(ctx, SAUCE, BASKET, lambda now: spot)
    hand, upright = lower.target(held, held)
    assert upright is None and np.allclose(hand[:2], spot[:2])
    point, tipped_hand = turn.target(held, held)
    assert np.allclose(point, hand)
    assert np.allclose(tipped_hand[:, 1], ctx.rotation[:, 1])  # about the fingers' axis
    angle = np.arccos(np.clip((np.trace(ctx.rotation.T @ tipped_hand) - 1.0) / 2.0, -1.0, 1.0))
    assert angle == pytest.approx(TIP_ANGLE)
    assert tipped_hand[:2, 2] @ (ctx.base_xy[:2] - spot[:2]) > 0.0
    hang = posed_corners(ctx, held, SAUCE) + (held.position(SAUCE) - held.tcp)
    turn_vector = Rotation.from_matrix(tipped_hand @ ctx.rotation.T).as_rotvec()
    lowest = [float(np.min((hang @ Rotation.from_rotvec(turn_vector * a).as_matrix().T)[:, 2]))
              + hand[2] for a in np.linspace(0.0, 1.0, 25)]  # fmt: skip
    assert min(lowest) == pytest.approx(top + TIP_DROP, abs=2e-3)
    assert min(lowest) >= top + TIP_DROP - 2e-3
    assert np.allclose(back.target(held, held)[1], ctx.rotation)


@pytest.mark.slow
def test_the_can_lands_on_the_lying_sauce_in_the_basket(capsys) -> None:
    """State 41 within its 520 steps: the sauce's place-in holds (lying in the basket) and
    the episode succeeds (0 / 10 on states 40-49 at e8a0c3b: the can stood on the
    standing sauce, its origin above the box)."""
    episode = scripted_episode(capsys, "libero_10_object", 0, 41)
    assert episode["success"], episode["trace"]
    assert any(f"place-in {SAUCE}" in line and "ok" in line for line in episode["trace"])
