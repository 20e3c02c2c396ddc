"""Disturbances of the kitchen's world: the cube knocked away after a grasp, the door left
part open, the valve moved from its file place.

The executor must notice from its percepts alone (the grasp detector loses the cube, the
pose estimator sees it elsewhere; the pose estimator reads the door's travel) and act on
the object where it now lies.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from osg_control.data.collect import placed_start_options
from osg_control.domain.contract import SkillEnv
from osg_control.domain.frames import sample_placements
from osg_control.execution.executor import Executor
from osg_control.kitchen.env import KitchenEnv
from osg_control.kitchen.skills import CUBE
from osg_control.kitchen.valve import VALVE_HINGE, VALVE_SHIFT

GOAL = ("cube-lifted",)
"""The task of a knocked-cube episode."""
GRASP_SETTLE_STEPS = 3
"""Steps the cube is held (truth) before it is knocked away: the grasp has closed."""


def displace_cube(env: KitchenEnv, offset: np.ndarray) -> None:
    """Teleport the cube by ``offset`` (x, y) [m] onto the counter, at rest."""
    adr = env.scene.cube_qpos
    env.data.qpos[adr : adr + 2] += np.asarray(offset, dtype=float)[:2]
    env.data.qpos[adr + 2] = CUBE.rest_z
    env.data.qpos[adr + 3 : adr + 7] = (1.0, 0.0, 0.0, 0.0)
    dof = env.model.jnt_dofadr[env.model.joint("cube_free").id]
    env.data.qvel[dof : dof + 6] = 0.0
    mujoco.mj_forward(env.model, env.data)


class CubeKnock:
    """An ``Executor.on_step`` hook that knocks the cube ``low``-``high`` m away in a random
    direction once it has been held (truth) for ``GRASP_SETTLE_STEPS`` steps, once."""

    def __init__(self, rng: np.random.Generator, low: float = 0.03, high: float = 0.06) -> None:
        distance = float(rng.uniform(low, high))
        angle = float(rng.uniform(0, 2 * np.pi))
        self.offset = distance * np.array([np.cos(angle), np.sin(angle)])
        self.fired = False
        self._held = 0

    def __call__(self, env: SkillEnv) -> None:
        if self.fired:
            return
        if not isinstance(env, KitchenEnv):
            raise TypeError(f"CubeKnock knocks the kitchen's cube, not {type(env).__name__}'s")
        self._held = self._held + 1 if env.world().cube_grasped else 0
        if self._held >= GRASP_SETTLE_STEPS:
            displace_cube(env, self.offset)
            self.fired = True


@dataclass(frozen=True)
class KnockedEpisode:
    """How one knocked-cube episode went (scored on the simulator's truth)."""

    knocked: bool
    recovered: bool
    replans: int


def knocked_cube_episode(
    executor: Executor, env: KitchenEnv, rng: np.random.Generator
) -> KnockedEpisode:
    """Place the cube uniformly in its region, start at home, run ``GOAL`` with the cube
    knocked 3-6 cm away once it has been grasped (``CubeKnock``)."""
    domain = executor.domain
    skill = domain.skill("move-home-to-cube")
    options = placed_start_options(domain, env, skill, sample_placements(domain, rng))
    options["position"] = domain.nodes["home"].position
    obs, _ = env.reset(seed=int(rng.integers(2**31)), options=options)
    knock = CubeKnock(rng)
    executor.on_step = knock
    try:
        result = executor.execute(list(GOAL), env, obs)
    finally:
        executor.on_step = None
    recovered = knock.fired and set(GOAL) <= env.facts()
    return KnockedEpisode(knock.fired, recovered, result.replans)


DOOR_GOAL = ("door-open",)
"""The task of a part-open-door episode."""


@dataclass(frozen=True)
class PartOpenEpisode:
    """How one part-open-door episode went (scored on the simulator's truth)."""

    travel: float
    opened: bool
    grabs: int
    grabs_held: int


def part_open_door_episode(
    executor: Executor, env: KitchenEnv, rng: np.random.Generator, low: float, high: float
) -> PartOpenEpisode:
    """Slide the door to a travel uniform in [``low``, ``high``] m (as a slide that lost the
    handle leaves it), start within 5 cm of ``door-front`` with the hand empty and run
    ``DOOR_GOAL``; count the ``grab-handle`` runs and those that held the handle (a grab
    that heads for the shut door's handle times out)."""
    travel = float(rng.uniform(low, high))
    options = {
        "position": executor.domain.nodes["door-front"].position,
        "radius": 0.05,
        "gripper": "open",
        "world": {"door_opening": travel},
    }
    obs, _ = env.reset(seed=int(rng.integers(2**31)), options=options)
    result = executor.execute(list(DOOR_GOAL), env, obs)
    grabs = [o for o in result.outcomes if o.skill == "grab-handle"]
    return PartOpenEpisode(
        travel, set(DOOR_GOAL) <= env.facts(), len(grabs), sum(o.success for o in grabs)
    )


VALVE_GOAL = ("valve-open", "hand-empty")
"""The task of a moved-valve episode (``turn-valve``'s goal)."""


@dataclass(frozen=True)
class MovedValveEpisode:
    """How one moved-valve episode went (scored on the simulator's truth)."""

    shift: tuple[float, float]
    opened: bool
    replans: int


def moved_valve_episode(
    executor: Executor, env: KitchenEnv, rng: np.random.Generator, shift: float = VALVE_SHIFT
) -> MovedValveEpisode:
    """Move the valve by a shift uniform in [-``shift``, ``shift``] m along x and y from its
    file place (the ``valve_pos`` option), start within 5 cm of ``home`` with the hand
    empty and run ``VALVE_GOAL``."""
    dx, dy = (float(v) for v in rng.uniform(-shift, shift, 2))
    options = {
        "position": executor.domain.nodes["home"].position,
        "radius": 0.05,
        "gripper": "open",
        "world": {"valve_pos": [VALVE_HINGE[0] + dx, VALVE_HINGE[1] + dy]},
    }
    obs, _ = env.reset(seed=int(rng.integers(2**31)), options=options)
    result = executor.execute(list(VALVE_GOAL), env, obs)
    return MovedValveEpisode((dx, dy), set(VALVE_GOAL) <= env.facts(), result.replans)
