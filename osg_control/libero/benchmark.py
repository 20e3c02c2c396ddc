"""The LIBERO benchmark's protocol: an episode is one of a task's fixed initial states, run
for at most the suite's published step budget, scored by the env's own ``check_success()``.

A policy (``LiberoPolicy``) decides each step from a percept (``perception``: the env's
observation and the fixture sensor) and the scene's static description; the harness reads
the simulator's verdict only to score. The summary (``summarise``) is what ``osg --domain
libero evaluate benchmark --json`` prints: per-task success, the overall rate and its 95 %
Wilson interval, the suite, the perception and the step budget.
"""

from __future__ import annotations

import hashlib
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any, Protocol

import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.evaluation.benchmark import Z95
from osg_control.evaluation.check import wilson_interval
from osg_control.libero.env import LiberoEnv
from osg_control.libero.perception import FIXTURE_NOISE, LiberoPercept, LiberoPerception
from osg_control.libero.problem import LiberoProblem
from osg_control.libero.robot import mounted_panda
from osg_control.libero.scene import Scene
from osg_control.libero.suites import max_steps
from osg_control.parallel import LocalExecutor

PERCEPTION = "env"
"""What the policies decide from: the env's observation (robot proprio, object poses) and
the fixture sensor's noisy joint readings (``perception.FixtureSensor``)."""


class LiberoPolicy(Protocol):
    """Decides a LIBERO env's actions from its observations."""

    name: str

    def start(
        self, problem: LiberoProblem, robot: RobotDescription, scene: Scene,
        percept: LiberoPercept,
    ) -> None:  # fmt: skip
        """Begin an episode of ``problem`` with the arm ``robot`` (where the scene stands
        it) in ``scene`` at ``percept``."""
        ...

    def act(self, percept: LiberoPercept) -> np.ndarray:
        """The next action (the env's controller's; ``env.CONTROLLER``)."""
        ...


PolicyFactory = Callable[[], LiberoPolicy]
"""Builds a policy in the worker that runs the episodes (a module-level function)."""


@dataclass(frozen=True)
class Episode:
    """One episode's outcome."""

    task: int
    init_state: int
    success: bool
    steps: int
    reset_s: float
    step_s: float
    trace: tuple[str, ...] = ()
    actions_sha256: str = ""
    """The SHA-256 of every action sent, as float64 bytes in order: equal digests are the
    same trajectory (the determinism check of a run against another)."""


@dataclass(frozen=True)
class Job:
    """The episodes of one task run in one worker (one env built)."""

    suite: str
    task: int
    init_states: tuple[int, ...]
    policy: PolicyFactory
    max_steps: int
    seed: int = 0


def run_job(job: Job) -> list[Episode]:
    """Run a job's episodes: reset to the initial state, step the policy on percepts until
    the env's ``check_success()`` holds or the step budget is spent. LIBERO's fixture
    placement and the fixture sensor's noise of initial state ``s`` are seeded by
    ``(job.seed, s)`` (``env.episode_seeds``): an episode is the same in any job."""
    env = LiberoEnv(job.suite, job.task)
    robot = mounted_panda(env.sim)
    perception = LiberoPerception(env, job.seed)
    policy = job.policy()
    episodes = []
    try:
        for state in job.init_states:
            start = time.process_time()
            obs = env.reset(state, job.seed)
            scene, percept = perception.reset(obs, state)
            reset_s = time.process_time() - start
            policy.start(env.problem, robot, scene, percept)
            success = env.check_success()
            start = time.process_time()
            digest = hashlib.sha256()
            while not success and env.steps < job.max_steps:
                action = np.asarray(policy.act(percept), dtype=np.float64)
                digest.update(action.tobytes())
                percept = perception.percept(env.step(action))
                success = env.check_success()
            step_s = (time.process_time() - start) / max(env.steps, 1)
            trace = tuple(getattr(policy, "trace", ()))
            episodes.append(Episode(job.task, state, success, env.steps, reset_s, step_s, trace,
                                    digest.hexdigest()))  # fmt: skip
    finally:
        env.close()
    return episodes


def run_suite(
    suite: str,
    tasks: Sequence[int],
    init_states: Sequence[int],
    policy: PolicyFactory,
    workers: int = 1,
    seed: int = 0,
) -> list[Episode]:
    """Every (task, initial state) episode, a task's episodes in one worker (arguments
    checked by the caller: ``tasks.check_task_indices``, ``suites.parse_init_states``);
    ``seed`` seeds the fixture sensor's noise."""
    jobs = [Job(suite, t, tuple(init_states), policy, max_steps(suite), seed) for t in tasks]
    episodes: list[Episode] = []
    for done in LocalExecutor(workers).map(run_job, jobs):
        episodes += done
    return episodes


def operator_outcomes(episodes: Sequence[Episode]) -> dict[str, dict[str, int]]:
    """How often each operator ran and how often its effect was perceived, from the
    episodes' traces (``"<step> <operator> <args>: ok"`` or ``": FAILED"``)."""
    counts: dict[str, dict[str, int]] = {}
    for episode in episodes:
        for line in episode.trace:
            words = line.split()
            if len(words) > 2 and words[-1] in ("ok", "FAILED"):
                row = counts.setdefault(words[1], {"runs": 0, "ok": 0})
                row["runs"] += 1
                row["ok"] += words[-1] == "ok"
    return dict(sorted(counts.items()))


def summarise(
    suite: str, policy_name: str, episodes: Sequence[Episode], seed: int = 0
) -> dict[str, Any]:
    """The JSON summary: per-task and overall success with 95 % Wilson intervals, and
    each operator's runs and perceived successes (``operator_outcomes``)."""
    per_task: dict[str, Any] = {}
    for task in sorted({e.task for e in episodes}):
        mine = [e for e in episodes if e.task == task]
        wins = sum(e.success for e in mine)
        per_task[str(task)] = {
            "episodes": len(mine),
            "successes": wins,
            "success_rate": wins / len(mine),
            "init_states": [e.init_state for e in mine],
        }
    wins = sum(e.success for e in episodes)
    rate = wins / len(episodes) if episodes else 0.0
    low, high = wilson_interval(rate, len(episodes), Z95)
    return {
        "suite": suite,
        "policy": policy_name,
        "perception": PERCEPTION,
        "fixture_noise": FIXTURE_NOISE,
        "seed": seed,
        "max_steps": max_steps(suite),
        "episodes": len(episodes),
        "success_rate": rate,
        "interval_95": [low, high],
        "tasks": per_task,
        "operators": operator_outcomes(episodes),
        "timing": {
            "reset_s_mean": float(np.mean([e.reset_s for e in episodes])) if episodes else None,
            "step_s_mean": float(np.mean([e.step_s for e in episodes])) if episodes else None,
        },
        "episode_log": [asdict(e) for e in episodes],
    }
