"""One option of a plan run on the env: its policy, in its bound object's frame, until its
termination condition beta holds on the percepts, its step budget runs out, a precondition
it keeps and the domain watches is lost, or the env ends its episode.

The executor (``execution.executor``) strings options into plans; this module is the one
place an option's step loop and its ways of ending are written.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from osg_control.classifier.motion import MotionMemory
from osg_control.control.estimator import TcpTracker
from osg_control.domain.base import Domain
from osg_control.domain.binding import BoundSkill
from osg_control.domain.contract import SkillEnv
from osg_control.domain.frames import in_skill_frame, node_position, skill_offset
from osg_control.environment.arm_env import GRIPPER_OPEN_CMD
from osg_control.environment.success import success_holds
from osg_control.execution.objects import ObjectTracker
from osg_control.execution.results import Policy, SkillOutcome

TIME_LIMIT = "the env's episode time limit was reached"
"""The failure of a skill whose env step came back truncated (e.g. a gymnasium
``TimeLimit``): the episode is over, so the execution ends without replanning."""
EPISODE_ENDED = "the env ended its episode"
"""The failure of a step sequence cut short because the env's episode is over
(``env.episode_over``: a step came back terminated, e.g. FrankaKitchen's tasks all done, or
truncated): by Gymnasium's protocol no further step is taken, so the execution ends there
and succeeds if its goal facts hold."""
GRASP_GRACE_STEPS = 5
"""Steps a watched fact may be false before the skill is stopped (a grasp's contact may
flicker for a few steps in the offline data)."""
GRIPPER_OPEN_STEPS = 5
"""Control steps that open an empty but closed gripper in place."""


@dataclass
class OptionRun:
    """What an option's run takes from the executor that runs it.

    Attributes:
        domain: the domain (nodes, watched facts, the recorded skills).
        policy: the option's policy (observation in its frame -> action).
        motion: the executor's memory of the commands sent (the classifier's input).
        on_step: called after every env step (e.g. to record video frames), or None.
    """

    domain: Domain
    policy: Policy
    motion: MotionMemory
    on_step: Callable[[SkillEnv], Any] | None = None


def run_option(
    run: OptionRun,
    env: SkillEnv,
    bound: BoundSkill,
    obs: np.ndarray,
    tracker: TcpTracker | None = None,
    objects: ObjectTracker | None = None,
) -> tuple[SkillOutcome, np.ndarray]:
    """Run one option until beta holds on the percepts, its step budget runs out or it
    loses a watched precondition (``Domain.watched_facts``) from the perceived facts.

    ``bound``: a plan step's bound skill (or a spec wrapped as its recorded binding): the
    lifted skill's policy in its bound object's frame, its facts and watched preconditions
    those of its objects (which cube is held). ``tracker``, if given, turns each
    observation into the policy's input and into the TCP position beta is checked on; it
    reads every observation and is told every action of the skill. ``objects`` estimates
    where the objects are from every percept (default: a new one); a skill acting in an
    object's frame sees the TCP relative to it and ends where it is (``domain.frames``).
    """
    domain, skill = run.domain, bound.skill
    recorded = domain.skills_by_name[skill.name]
    end = domain.nodes[skill.end]
    if objects is None:
        objects = ObjectTracker(domain, perception=env.perception)
        objects.update(env.percept())
    kept = (recorded.preconditions - recorded.del_effects) & domain.watched_facts
    watched = {bound.fact(fact) for fact in kept}
    started = time.perf_counter()

    def outcome(success: bool, steps: int, failure: str | None = None) -> SkillOutcome:
        return SkillOutcome(skill.name, success, steps, time.perf_counter() - started,
                            failure=failure)  # fmt: skip

    lost_steps = 0
    for step in range(1, skill.max_steps + 1):
        seen = obs if tracker is None else tracker.read(obs)
        offset = skill_offset(domain, skill, bound.offsets(objects.offsets()))
        action = run.policy(in_skill_frame(seen, offset))
        if tracker is not None:
            tracker.acted(action)
        run.motion.commanded(action)
        obs, _reward, terminated, truncated, info = env.step(action)
        if run.on_step is not None:
            run.on_step(env)
        if "failure" in info:
            return outcome(False, step, info["failure"]), obs
        percept = env.percept()
        objects.update(percept)
        position = (percept.state if tracker is None else tracker.read(obs))[:3]
        goal = node_position(domain.nodes, end.name, bound.offsets(objects.offsets()))
        if success_holds(skill, end, position, percept.state[7], percept.facts, goal):
            return outcome(True, step), obs
        ended = episode_end(terminated, truncated)
        if ended:
            return outcome(False, step, ended), obs
        lost = watched - percept.facts
        lost_steps = lost_steps + 1 if lost else 0
        if lost_steps >= GRASP_GRACE_STEPS:
            return outcome(False, step, f"precondition {sorted(lost)} lost"), obs
    return outcome(False, skill.max_steps, f"timeout after {skill.max_steps} steps"), obs


def open_gripper(env: SkillEnv, steps: int = GRIPPER_OPEN_STEPS) -> tuple[np.ndarray, str | None]:
    """Open an empty but closed gripper in place (recovery before a movement skill, whose
    termination needs it open); returns the observation and a divergence, or the env's
    episode ending (no step is taken after it), if any."""
    obs = env.observe()
    for _ in range(steps):
        obs, _reward, terminated, truncated, info = env.step(
            np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, GRIPPER_OPEN_CMD])
        )
        failure = info.get("failure") or episode_end(terminated, truncated)
        if failure:
            return obs, f"opening the gripper: {failure}"
    return obs, None


def episode_end(terminated: bool, truncated: bool) -> str | None:
    """The failure of a step that ended the env's episode (``TIME_LIMIT`` when truncated),
    else None: by Gymnasium's protocol no step may follow it."""
    if truncated:
        return TIME_LIMIT
    return EPISODE_ENDED if terminated else None
