"""``MiniEnv``: the Panda at a table with a push button (``ArmEnv`` with the button's world)."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from minidomain.domain import NODES, SKILLS, facts_of
from osg_control.control.robot import (
    ARM_JOINTS,
    FINGER_JOINTS,
    FINGER_OPEN,
    HOME_KEY,
    HOME_Q,
    panda_spec,
)
from osg_control.domain.spec import SkillSpec
from osg_control.environment.arm_env import ArmEnv, EnvConfig

SCENE = Path(__file__).with_name("scene.xml")
PRESSED_START = 0.015
"""Button depth [m] of a start with ``button-pressed`` among its facts."""


def build_model() -> mujoco.MjModel:
    """``scene.xml`` with the Panda at the origin and a full-state ``HOME_KEY`` keyframe."""
    spec = mujoco.MjSpec.from_file(str(SCENE))
    robot = panda_spec(with_fingers=True)
    for key in list(robot.keys):  # the scene's keyframe must cover its own joints too
        robot.delete(key)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")
        spec.attach(robot, frame=spec.worldbody.add_frame(), prefix="")
        model = spec.compile()
    data = mujoco.MjData(model)
    qpos = data.qpos.copy()  # the button up (its qpos0)
    ctrl = np.zeros(model.nu)
    for name, value in zip(ARM_JOINTS, HOME_Q, strict=True):
        qpos[model.joint(name).qposadr[0]] = value
        ctrl[model.actuator(name).id] = value
    for name in FINGER_JOINTS:
        qpos[model.joint(name).qposadr[0]] = FINGER_OPEN
    ctrl[model.actuator("gripper").id] = FINGER_OPEN
    spec.add_key(name=HOME_KEY, qpos=qpos, ctrl=ctrl)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")
        return spec.compile()


class MiniEnv(ArmEnv):
    """The minimal domain's env: world state ``[button_depth]``, facts ``domain.facts_of``."""

    def __init__(
        self,
        skill: str | SkillSpec | None = None,
        config: EnvConfig | None = None,
        render_mode: str | None = None,
    ) -> None:
        spec = {s.name: s for s in SKILLS}[skill] if isinstance(skill, str) else skill
        super().__init__(NODES, "home", spec, config or EnvConfig(), render_mode)
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
