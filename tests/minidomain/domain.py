"""The minimal domain's data and its ``Domain`` factory (no MuJoCo import: the env loads
only when ``make_env`` is called).

Graph::

    home <-- move-button-to-home --- above-button --- press-button --> button-down
         --- move-home-to-button -->

World state: one field, ``button_depth`` [m] (how far the cap is pushed down); facts:
``button-pressed`` from ``PRESSED_DEPTH`` on, else ``button-up``; ``hand-empty`` always
holds (there is nothing to grasp).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from osg_control.domain.base import Domain, StartRegion, Task
from osg_control.domain.spec import MOVEMENT, Node, ScriptParams, SkillSpec, Waypoint

DOMAIN_NAME = "mini"

BUTTON_XY = (0.50, 0.10)
"""The button cap's centre (x, y) [m]; its top is at z = 0.06 when up (``scene.xml``)."""
PRESSED_DEPTH = 0.01
"""Depth [m] from which the button counts as pressed (its travel is 3 cm)."""

NODES: dict[str, Node] = {
    node.name: node
    for node in (
        Node("home", (0.40, 0.00, 0.30)),
        Node("above-button", (*BUTTON_XY, 0.15)),
        # The open fingertips reach about 2.5 cm below the TCP: at z = 0.062 they hold the
        # cap about 2.3 cm down (pressed from 1 cm on; its travel ends at 3 cm).
        Node("button-down", (*BUTTON_XY, 0.062)),
    )
}

FACTS: tuple[str, ...] = ("hand-empty", "button-up", "button-pressed")
WORLD_FIELDS: tuple[str, ...] = ("button_depth",)
START_WORLD: tuple[str, ...] = ("hand-empty", "button-up")


def facts_of(world: np.ndarray) -> frozenset[str]:
    """The facts of a world-state vector (``WORLD_FIELDS``)."""
    pressed = float(world[0]) >= PRESSED_DEPTH
    return frozenset({"hand-empty", "button-pressed" if pressed else "button-up"})


SCRIPT = ScriptParams(
    threshold_mean=0.008, threshold_std=0.003, noise_mean=0.0, noise_std=0.004,
    steps_per_waypoint=25,
)  # fmt: skip
"""Algorithm 1's parameters: noisy (4 mm per step) but with a budget so generous that the
scripted skills always succeed; they are not tuned to the paper's 40-50 %."""


def _move(name: str, start: str, end: str) -> SkillSpec:
    return SkillSpec(
        name=name,
        kind=MOVEMENT,
        start=start,
        end=end,
        waypoints=(Waypoint(NODES[end].position, "open"),),
        preconditions=frozenset({"hand-empty"}),
        script=SCRIPT,
        max_steps=60,
        start_radius=0.03,
        start_angle=0.05,
    )


SKILLS: tuple[SkillSpec, ...] = (
    _move("move-home-to-button", "home", "above-button"),
    _move("move-button-to-home", "above-button", "home"),
    SkillSpec(
        name="press-button",
        kind="button",
        start="above-button",
        end="button-down",
        waypoints=(Waypoint(NODES["button-down"].position, "open"),),
        preconditions=frozenset({"hand-empty", "button-up"}),
        add_effects=frozenset({"button-pressed"}),
        del_effects=frozenset({"button-up"}),
        script=SCRIPT,
        max_steps=60,
    ),
)

TASKS: tuple[Task, ...] = (
    Task("press", ("button-pressed",), node="home", description="press the button"),
)

START_REGIONS: tuple[StartRegion, ...] = (
    StartRegion("home", NODES["home"].position, radius=0.05),
    StartRegion("above-button", NODES["above-button"].position, radius=0.05),
)


def make_env(**kwargs: Any) -> Any:
    """A ``MiniEnv`` (imported here: MuJoCo loads only when an env is made)."""
    from minidomain.env import MiniEnv

    return MiniEnv(**kwargs)


def mini_domain() -> Domain:
    """The minimal domain (register it with ``register_domain(DOMAIN_NAME, mini_domain)``)."""
    return Domain(
        name=DOMAIN_NAME,
        description="a Panda at a table with one push button (the test suite's example)",
        nodes=NODES,
        facts=FACTS,
        skills=SKILLS,
        tasks=TASKS,
        start_regions=START_REGIONS,
        start_world=START_WORLD,
        home="home",
        world_fields=WORLD_FIELDS,
        facts_of=facts_of,
        make_env=make_env,
        hand_empty="hand-empty",
        robot="panda",
    )
