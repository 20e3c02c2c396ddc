"""The burners: the bottom and top knobs turned by a sweep of the closed fingers.

Geometry, measurements and what failed first: docs/franka-kitchen.md ("Burners").
"""

from __future__ import annotations

import numpy as np

from osg_control.domain.spec import Node, SkillSpec
from osg_control.franka.poses import SCRIPT, at, turned, wp

# Burner knobs: a vertical bar (2.8 cm wide in x, 9.6 cm tall, y 0.622-0.658) in front of a
# disk, turning about world -y; the bottom burner's knob (qpos 11) is centred at
# (-0.256, z 2.226), the top burner's (qpos 15) at (-0.256, z 2.34). Grasp the bar with the
# fingers across x and twist the hand about +y (the knob's q goes negative); the library
# counts a burner done once its knob is within 0.3 of -0.88 / -0.92.
KNOB_X = -0.256
KNOB_Y = 0.61
KNOB_FRONT_Y = 0.53
BOTTOM_KNOB_Z = 2.226
TOP_KNOB_Z = 2.34
KNOB_RADIUS = 0.035
"""The fingers' arc about the knob's axis [m] (the bar reaches 0.048)."""
KNOB_ARC = (-0.8, -0.4, 0.0, 0.3, 0.6, 0.9, 1.2)
"""The fingers' angles on the arc [rad from +z toward +x]; the bar turns ahead of them. Up
to 0.9 the scripted bottom knob ended at -0.59 rad on average (done, below -0.58, in 7 of
20 noisy episodes) and the learned turn needed two or three attempts; to 1.2, -0.68 (16 of
20; noise-free -1.11), one attempt. To 1.5 the noise-free script over-turned it to -1.24,
outside the library's ball of 0.3 about -0.88."""
KNOB_TURNED_ANGLE = 0.9
"""The arc angle the turned node backs off in front of."""
KNOB_ARC_STEPS = 5
KNOB_PITCH = -0.3
"""The tool tilted down about world x [rad]: level, this low target puts joint 6 at its
limit (the TCP stalls 15 cm short); 0.3 rad down it is reached in 22 steps."""
KNOB_GRASP_QUAT = turned((1.0, 0.0, 0.0), KNOB_PITCH)


def knob_point(z: float, angle: float, y: float = KNOB_Y) -> tuple[float, float, float]:
    """The TCP on the push's arc about the knob centred at ``(KNOB_X, z)``."""
    return (
        round(KNOB_X + KNOB_RADIUS * float(np.sin(angle)), 4),
        y,
        round(z + KNOB_RADIUS * float(np.cos(angle)), 4),
    )


def _knob_front(z: float, side: int) -> tuple[float, float, float]:
    """In front of the arc's start (``side`` -1) or of the turned knob (+1), clear of the
    bar."""
    return knob_point(z, KNOB_ARC[0] if side < 0 else KNOB_TURNED_ANGLE, KNOB_FRONT_Y)


_BOTTOM_TURNED = Node(
    "bottom-knob-turned", _knob_front(BOTTOM_KNOB_Z, 1), "closed", KNOB_GRASP_QUAT
)
_TOP_TURNED = Node("top-knob-turned", _knob_front(TOP_KNOB_Z, 1), "closed", KNOB_GRASP_QUAT)
BURNER_NODES: tuple[Node, ...] = (
    Node("bottom-knob-front", _knob_front(BOTTOM_KNOB_Z, -1), "closed", KNOB_GRASP_QUAT),
    _BOTTOM_TURNED,
    Node("top-knob-front", _knob_front(TOP_KNOB_Z, -1), "closed", KNOB_GRASP_QUAT),
    _TOP_TURNED,
)
"""In front of each knob's arc start (closed fingers) and where the sweep ends."""


def _turn_knob(name: str, level: str, z: float, on: str, off: str, turned_node: Node) -> SkillSpec:
    """Push the top of a burner knob's bar along +x with the closed fingers (the knob turns
    negative), then back off to ``turned_node``."""
    return SkillSpec(
        name=name,
        kind="push",
        start=f"{level}-knob-front",
        end=f"{level}-knob-turned",
        waypoints=(
            wp(
                knob_point(z, KNOB_ARC[0]),
                "closed",
                steps=10,
                reach=0.008,
                orientation=KNOB_GRASP_QUAT,
            ),
            *(
                wp(
                    knob_point(z, a),
                    "closed",
                    steps=KNOB_ARC_STEPS,
                    reach=0.008,
                    orientation=KNOB_GRASP_QUAT,
                )
                for a in KNOB_ARC[1:]
            ),
            at(turned_node, steps=8),
        ),
        preconditions=frozenset({"hand-empty", off}),
        add_effects=frozenset({on}),
        del_effects=frozenset({off}),
        script=SCRIPT,
        success_tolerance=0.03,
        max_steps=60,
    )


BURNER_SKILLS: tuple[SkillSpec, ...] = (
    _turn_knob(
        "turn-bottom-knob",
        "bottom",
        BOTTOM_KNOB_Z,
        "bottom-burner-on",
        "bottom-burner-off",
        _BOTTOM_TURNED,
    ),
    _turn_knob("turn-top-knob", "top", TOP_KNOB_Z, "top-burner-on", "top-burner-off", _TOP_TURNED),
)
