"""The learned pick's close on a stalled descent: a rule, not learned.

The scripted pick closes when its descent reaches the grasp point (``pick_place.DESCENT_
TOLERANCE``) or, when the hand stops above it (a standing book, a second moka pot, a tall
bottle), when its 40 steps run out. The network learned the first but not the second (one
closing step among some 25 open hover steps at the same features) and hovers until its
budget is spent. ``StallClose`` states the scripted pick's percept rule for it: with the
hand open, come down ``DESCENDED`` since the skill started (a hand still at the hover is
not descending), over the grasp point (``LATERAL`` across) but farther than the tolerance
from it, and come less than ``STALL_APPROACH`` closer to it over the last ``STALL_STEPS``
percepts both down and across (a hand still closing in across, its height unchanged, is
on its way), close, and keep it closed; if the object is not held once the fingers had
``CLOSING_STEPS`` to close, the pick has missed and ends (the network would lift the
empty hand for the rest of its budget, and the retry start far above). The network still
decides every motion and every other close.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from osg_control.libero.drive import GRIPPER_CLOSED
from osg_control.libero.pick_place import CLOSING_STEPS

STALL_STEPS = 5
"""Percepts over which a stalled descent is judged: a descending hand comes ~4 cm closer."""
STALL_APPROACH = 0.002
"""A hand that came less than this closer down and across over ``STALL_STEPS`` percepts has
stalled [m]."""
DESCENDED = 0.03
"""How far below its height at the skill's start the hand must have come [m]: the network
may pause at the hover before it descends (a butter box, 1 cm down)."""
LATERAL = 0.02
"""How far across from the grasp point a stalled hand may be and still close [m]."""


class StallClose:
    """Closes the gripper of a learned pick whose descent stalled over the grasp point."""

    def __init__(self, tolerance: float) -> None:
        self.tolerance = tolerance
        self.offsets: deque[tuple[float, float]] = deque(maxlen=STALL_STEPS + 1)
        self.start_height: float | None = None
        self.closed = False
        self.closed_steps = 0

    def gripper(self, to_grasp: np.ndarray, command: float) -> float:
        """The gripper command to send given the network's ``command`` and the TCP minus
        the grasp point at this percept (call once a step)."""
        offset = (float(to_grasp[2]), float(np.linalg.norm(to_grasp[:2])))  # down, across
        self.offsets.append(offset)
        if self.start_height is None:
            self.start_height = offset[0]
        if not self.closed and command != GRIPPER_CLOSED:
            before = self.offsets[0]
            stalled = len(self.offsets) == self.offsets.maxlen and all(
                b - o < STALL_APPROACH for b, o in zip(before, offset, strict=True)
            )
            descended = self.start_height - offset[0] >= DESCENDED
            far = float(np.linalg.norm(to_grasp)) > self.tolerance
            self.closed = stalled and descended and far and offset[1] < LATERAL
        self.closed_steps += self.closed
        return GRIPPER_CLOSED if self.closed else command

    def missed(self, holding: bool) -> bool:
        """Whether the rule's close has missed: given ``CLOSING_STEPS`` and not ``holding``."""
        return self.closed_steps >= CLOSING_STEPS and not holding
