"""``MiniEnv``: the Panda at a table with a push button (``ArmEnv`` with the button's world)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from minidomain.domain import FACTS, NODES, SKILLS, facts_of
from osg_control.control.scene_model import home_keyed_model, with_robot
from osg_control.domain.spec import SkillSpec
from osg_control.environment.arm_env import ArmEnv, EnvConfig
from osg_control.perception.sensors import POSITION
from osg_control.robots.registry import get_robot

SCENE = Path(__file__).with_name("scene.xml")
PRESSED_START = 0.015
"""Button depth [m] of a start with ``button-pressed`` among its facts."""


def build_model() -> mujoco.MjModel:
    """``scene.xml`` with the Panda at the origin and a full-state ``HOME_KEY`` keyframe (the
    button up: its rest value)."""
    robot = get_robot("panda")
    return home_keyed_model(with_robot(mujoco.MjSpec.from_file(str(SCENE)), robot), robot)


class MiniEnv(ArmEnv):
    """The minimal domain's env: world state ``[button_depth]``, facts ``domain.facts_of``."""

    world_facts = FACTS
    world_options = ("button_depth",)
    world_sensors = {"button_depth": POSITION}  # the pose estimator sees the button's travel

    def __init__(
        self,
        skill: str | SkillSpec | None = None,
        config: EnvConfig | None = None,
        render_mode: str | None = None,
    ) -> None:
        spec = {s.name: s for s in SKILLS}[skill] if isinstance(skill, str) else skill
        super().__init__(
            NODES, "home", spec, config or EnvConfig(), render_mode, robot=get_robot("panda")
        )
        self._button_qpos = self.model.joint("button_slide").qposadr[0]

    def build_model(self) -> mujoco.MjModel:
        return build_model()

    def read_world(self) -> np.ndarray:
        """``[button_depth]``: how far [m] the cap is pushed down (a fresh array)."""
        return np.array([-float(self.data.qpos[self._button_qpos])])

    def facts_of(self, world: np.ndarray) -> frozenset[str]:
        return facts_of(world)

    def place_world(
        self, world: dict[str, Any], facts: frozenset[str], holding: str | None
    ) -> None:
        """The button up, or down if ``button-pressed`` is a start fact (or ``world`` gives
        ``button_depth``)."""
        default = PRESSED_START if "button-pressed" in facts else 0.0
        depth = float(world.get("button_depth", default))
        self.data.qpos[self._button_qpos] = -depth
