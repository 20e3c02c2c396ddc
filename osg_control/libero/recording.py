"""Algorithm 1's data for a LIBERO operator: the scripted-plan executor runs a task from
its fixed initial states, and while the recorded operator (``pick`` / ``pick-out``) runs,
its scripted controller's commands are turned into lifted actions (``features``),
perturbed with seeded Gaussian exploration noise, executed, and recorded with the lifted
observation before and after each step. The reward is the operator's effect perceived
(``pick_place.holding_ok``): the first step after which it holds ends the episode. The
other operators run unperturbed and unrecorded; an env episode stops once the plan's picks
are done (or the suite's step budget is spent).

Everything recorded comes from percepts and the scene's description; the simulator only
sets the initial states up. The same seed gives the same data: LIBERO's fixture placement
and the fixture sensor draw from ``env.episode_seeds``, the noise from
``(seed, task, initial state)``.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from osg_control.domain.spec import ScriptParams, SkillSpec, Waypoint
from osg_control.libero.executor import MAX_REPLANS, PlanExecutor
from osg_control.libero.features import (
    ACTION_SCALE,
    GripperMemory,
    command,
    lifted_action,
    observe,
)
from osg_control.libero.legs import HOVER, Context, Leg, LegRunner, Runner
from osg_control.libero.operators import PICKS
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.pick_place import LIFT, holding_ok
from osg_control.libero.skill_data import Recorded

OPERATORS: dict[str, tuple[str, ...]] = {"pick": PICKS}
"""A recordable skill -> the operators of ``osg-libero`` it runs (one network for both:
taking an object off a thing or out of a region is the same motion)."""
NOISE_STD = 0.005
"""The exploration noise's std on the TCP target offset [m] (``--noise-std``); the wrist
yaw's is scaled by the bounds' ratio (``features.ACTION_SCALE``), the gripper's is 0."""
SKILL_MAX_STEPS = 150
"""A learned pick's step budget (the scripted pick's legs allow 172 steps; its recorded
episodes are far shorter)."""


def pick_skill(noise_std: float = NOISE_STD) -> SkillSpec:
    """The ``pick`` skill as recorded: the script's waypoints in the grasp point's frame
    (hover, grasp point, lifted) and Algorithm 1's noise."""
    return SkillSpec(
        name="pick", kind="libero-pick", start="near", end="holding",
        waypoints=(Waypoint((0.0, 0.0, HOVER), "open"), Waypoint((0.0, 0.0, 0.0), "closed"),
                   Waypoint((0.0, 0.0, LIFT), "closed")),
        script=ScriptParams(threshold_mean=0.008, threshold_std=0.0, noise_std=noise_std),
        max_steps=SKILL_MAX_STEPS, parameters=(("o", "movable"), ("s", "thing")),
    )  # fmt: skip


def noise_scale(noise_std: float) -> np.ndarray:
    """The noise's std per lifted action component (position, yaw scaled; gripper 0)."""
    scale = ACTION_SCALE * noise_std / ACTION_SCALE[0]
    scale[-1] = 0.0
    return scale


class NoisyRecorder:
    """Runs a scripted operator's legs through lifted actions with exploration noise and
    records the steps (a ``legs.Runner``); hands its episode to ``done`` when the effect
    is perceived or the legs run out."""

    def __init__(
        self, ctx: Context, legs: list[Leg], obj: str, start_z: float,
        rng: np.random.Generator, noise: np.ndarray, done: Callable[[Recorded], None],
        where: tuple[int, int],
    ) -> None:  # fmt: skip
        self.ctx, self.legs, self.obj, self.start_z = ctx, LegRunner(legs, ctx), obj, start_z
        self.rng, self.noise, self.done = rng, noise, done
        self.episode = Recorded([], [], [], False, *where)
        self.gripper = GripperMemory()

    def act(self, percept: LiberoPercept) -> np.ndarray | None:
        """The next action; None when the episode is recorded."""
        episode = self.episode
        now = observe(self.ctx, percept, self.obj, self.start_z, self.gripper)
        if episode.actions:
            episode.next_observations.append(now)
            if holding_ok(self.ctx, percept, self.obj, self.start_z):
                episode.success = True
                self._finish()
                return None
        scripted = self.legs.command(percept)
        if scripted is None or len(episode.actions) >= SKILL_MAX_STEPS:
            self._finish()
            return None
        action = lifted_action(self.ctx, percept, *scripted)
        action = np.clip(action + self.rng.normal(0.0, 1.0, action.shape) * self.noise,
                         -ACTION_SCALE, ACTION_SCALE)  # fmt: skip
        position, rotation, gripper = command(self.ctx, percept, action)
        episode.observations.append(now)
        episode.actions.append(action.astype(np.float32))
        self.ctx.rotation = rotation
        self.gripper.given(gripper)
        return self.ctx.driver.action(percept.joints, position, rotation, gripper)

    def _finish(self) -> None:
        if self.episode.actions:
            self.done(self.episode)


class RecordingExecutor(PlanExecutor):
    """The scripted-plan executor whose ``skill`` operators run through ``NoisyRecorder``.

    Attributes:
        episodes: the recorded operator runs, in order.
    """

    name = "record"

    def __init__(self, skill: str, noise_std: float, planner: str = "auto") -> None:
        super().__init__(planner)
        self.operators = OPERATORS[skill]
        self.noise = noise_scale(noise_std)
        self.episodes: list[Recorded] = []
        self.rng = np.random.default_rng(0)
        self.where = (0, 0)
        self.failed = False

    def begin(self, rng: np.random.Generator, task: int, init_state: int) -> None:
        """Set the next episode's noise generator and where it runs (before ``start``)."""
        self.rng, self.where, self.failed = rng, (task, init_state), False

    def _runner(self, operator: str, args: tuple[str, ...], legs: list[Leg]) -> Runner:
        if operator not in self.operators:
            return super()._runner(operator, args, legs)
        return NoisyRecorder(self.ctx, legs, args[0], self.start_z, self.rng, self.noise,
                             self._recorded, self.where)  # fmt: skip

    def _recorded(self, episode: Recorded) -> None:
        self.episodes.append(episode)
        self.failed = not episode.success

    def picks_left(self) -> bool:
        """Whether the plan still has a recorded operator to run: one is running or
        queued, or the last one failed and a replan (which retries it) is left."""
        running = self.current is not None and self.current[0] in self.operators
        queued = any(op in self.operators for op, _ in self.queue)
        return running or queued or (self.failed and self.replans < MAX_REPLANS)


@dataclass(frozen=True)
class CollectJob:
    """The recording of one task's initial states (one env)."""

    suite: str
    task: int
    init_states: tuple[int, ...]
    skill: str
    seed: int
    noise_std: float
    max_steps: int


def noise_rng(seed: int, task: int, init_state: int) -> np.random.Generator:
    """The exploration noise's generator of one episode."""
    return np.random.default_rng([seed, task, init_state])


def collect_job(job: CollectJob) -> list[Recorded]:
    """Run the job's episodes and return the recorded operator runs."""
    from osg_control.libero.env import LiberoEnv
    from osg_control.libero.perception import LiberoPerception
    from osg_control.libero.robot import mounted_panda

    env = LiberoEnv(job.suite, job.task)
    recorder = RecordingExecutor(job.skill, job.noise_std)
    try:
        robot = mounted_panda(env.sim)
        perception = LiberoPerception(env, job.seed)
        for state in job.init_states:
            obs = env.reset(state, job.seed)
            scene, percept = perception.reset(obs, state)
            recorder.begin(noise_rng(job.seed, job.task, state), job.task, state)
            recorder.start(env.problem, robot, scene, percept)
            while env.steps < job.max_steps and recorder.picks_left():
                percept = perception.percept(env.step(recorder.act(percept)))
    finally:
        env.close()
    return recorder.episodes


def episodes_sha256(episodes: Sequence[Recorded]) -> str:
    """The digest of every recorded observation and action (the determinism check)."""
    digest = hashlib.sha256()
    for e in episodes:
        for rows in (e.observations, e.actions, e.next_observations):
            digest.update(np.asarray(rows, dtype=np.float32).tobytes())
        digest.update(bytes([e.success]))
    return digest.hexdigest()
