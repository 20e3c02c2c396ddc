"""Run a task end to end: classify the start, plan, execute options, reset joints, replan.

The only module where simulator, policies, classifier and planner meet. Given a goal (PDDL
world facts) and the env's current state:

Everything here decides from what the robot perceives (``env.percept()``: the perceived
state, and the facts the domain's detectors read from the perceived world); the
simulator's truth is for scoring the result, outside.

1. if the TCP is on a graph node, plan from it; if it is part-way along a manipulation
   skill's path (an interrupted skill), that skill is the entry; otherwise the classifier
   picks the entry (movement) skill among those whose recorded start facts
   (``SkillSpec.start_facts``) hold now. The planner plans from the entry's termination
   node, over the skill graph's costs (``round(-ln p * 1000)`` of the measured rates);
2. each option runs its policy until its termination condition beta holds (the skill's
   success predicate), its step budget runs out, or a precondition it keeps and the domain
   watches (``Domain.watched_facts``, e.g. a grasp) is lost for ``option.GRASP_GRACE_STEPS``
   steps; the joints are reset between skills;
3. on a failure (timeout, lost grasp, or the expected effect missing from the perceived
   facts) the state is re-read, re-classified and re-planned, up to ``max_replans`` times;
   a goal with no plan from the perceived facts while part of it has one (an object not
   seen yet) runs that part, then replans the whole from what is perceived then (each a
   replan).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from osg_control.classifier.motion import MotionMemory
from osg_control.control.divergence import is_divergence
from osg_control.control.estimator import (
    MOTION_MODEL,
    TcpFilter,
    TcpTracker,
    check_motion_model,
)
from osg_control.domain.base import Domain
from osg_control.domain.binding import BoundSkill, bind_step
from osg_control.domain.contract import SkillEnv
from osg_control.domain.frames import (
    Offsets,
    node_position,
)
from osg_control.domain.spec import SkillSpec
from osg_control.environment.arm_env import GRIPPER_OPEN_CMD, EnvConfig
from osg_control.errors import SimulationError
from osg_control.execution import MAX_REPLANS
from osg_control.execution.entry import EntryChoice
from osg_control.execution.goals import parse_goal
from osg_control.execution.locate import node_at
from osg_control.execution.objects import ObjectTracker
from osg_control.execution.option import (
    EPISODE_ENDED,
    GRIPPER_OPEN_STEPS,
    TIME_LIMIT,
    OptionRun,
    open_gripper,
    run_option,
)
from osg_control.execution.results import (
    EntryClassifier,
    ExecutionResult,
    Policy,
    SkillOutcome,
)
from osg_control.perception.spec import PerceptionSpec
from osg_control.planning.api import graph_domain
from osg_control.planning.graph import SkillGraph
from osg_control.planning.memo import PlanMemo


def task_env_config(perception: PerceptionSpec) -> EnvConfig:
    """The env options of a task execution: what the robot perceives and no episode
    truncation, since the executor bounds every skill by its own budget (a domain whose env
    has its own time limit, like FrankaKitchen-v1's, keeps it)."""
    return EnvConfig(perception=perception, max_steps=None)


class Executor:
    """Classify, plan and run options on a domain's env.

    Args:
        domain: the domain (nodes, skills, facts, watched facts).
        policies: skill name -> policy (e.g. ``policy.load_policies(dir)``).
        classifier: the state->skill classifier for starts off the graph.
        planner: a planner registry name (``"astar"`` default).
        max_replans: how many times a failed plan is re-planned (0 = the paper's executor).
        reset_joints: run the joint reset between skills.
        filter_gain: feed the policies a filtered TCP position (``estimator.TcpFilter``
            with this gain, carried across the skills of an execution), and locate the
            robot on the graph from it; None uses the raw observation (the paper's
            protocol).
        goal_aware_entry: choose the entry movement skill by the cost to the goal
            (``entry.EntryChoice.classify``); False: the classifier's argmax (the paper's executor).
        motion_model: the filter's ``(k_now, k_prev)`` (the defaults' own,
            ``load_executor``; default the kitchen's fit).
        graph: the skill graph whose costs plans minimise: the cost model, e.g. the
            defaults' measured success rates (``defaults.load_defaults(...).graph``,
            ``execution.bundle.measured_graph``), or ``planning.graph.graph_from_specs(domain)``
            for uniform costs, said explicitly.
    """

    def __init__(
        self,
        domain: Domain,
        policies: Mapping[str, Policy],
        classifier: EntryClassifier,
        graph: SkillGraph,
        planner: str = "astar",
        max_replans: int = 2,
        reset_joints: bool = True,
        filter_gain: float | None = None,
        goal_aware_entry: bool = True,
        motion_model: tuple[float, float] = MOTION_MODEL,
    ) -> None:
        if not isinstance(graph, SkillGraph):
            raise TypeError(
                f"Executor needs a SkillGraph cost model, got {type(graph).__name__}: pass "
                f"load_defaults(domain).graph or planning.graph.graph_from_specs(domain)"
            )
        missing = sorted(set(domain.skills_by_name) - set(policies))
        if missing:
            raise ValueError(f"domain {domain.name!r}: no policy for skills {missing}")
        if not (
            isinstance(max_replans, int | np.integer)
            and not isinstance(max_replans, bool)
            and 0 <= max_replans <= MAX_REPLANS
        ):
            raise ValueError(
                f"Executor max_replans must be a whole number in [0, {MAX_REPLANS}], "
                f"got {max_replans!r}"
            )
        if filter_gain is not None:
            TcpFilter(filter_gain, motion_model)  # refuses a bad gain or motion model
        motion_model = check_motion_model(motion_model)
        self.domain = domain
        self.skills = domain.skills_by_name
        self._plans = PlanMemo(domain, graph_domain(domain, graph))
        self.policies = policies
        self.entry = EntryChoice(domain, classifier, graph, self._plans)
        """Where a start off the graph enters it (``entry.EntryChoice``)."""
        self.planner = planner
        self.max_replans = max_replans
        self.reset_joints = reset_joints
        self.filter_gain = filter_gain
        self.goal_aware_entry = goal_aware_entry
        self.motion_model = motion_model
        self.on_step: Callable[[SkillEnv], Any] | None = None
        """Called after every env step (e.g. to record video frames)."""
        self.on_event: Callable[[str, dict[str, Any]], Any] | None = None
        """Called with ``(kind, fields)`` as an execution goes: ``plan`` (attempt, entry,
        plan), ``skill`` (name, target node, its position), ``outcome`` (skill, success,
        steps, failure), ``replan`` (attempt, failure), ``end`` (success, failure,
        replans); e.g. to record a run (``execution.recording``)."""
        self.motion = MotionMemory()
        """The TCP commands sent since ``execute`` began: the classifier's motion input."""

    @property
    def classifier(self) -> EntryClassifier:
        """The state -> movement-skill classifier of the entry choice."""
        return self.entry.classifier

    @property
    def graph(self) -> SkillGraph:
        """The cost model the plans and the entry choice minimise."""
        return self.entry.graph

    def plan(
        self,
        goal: Iterable[str],
        obs: np.ndarray,
        facts: Iterable[str],
        offsets: Offsets | None = None,
    ) -> tuple[str | None, list[str], Any]:
        """Choose the entry skill (if off the graph) and plan the rest; ``offsets``: where
        the objects are (anchored nodes move with them).

        Returns:
            ``(entry skill or None, plan, planner result)``; the entry and the plan's steps
            are ground operators, ``skill obj1 ...`` (``binding.bind_step``), the entry
            bound to the objects that make the goal cheapest (``EntryChoice.bind``).
        """
        facts = set(facts)
        goal = list(goal)
        offsets = offsets or {}
        node = node_at(self.domain, obs, facts, offsets)
        entry = None
        if node is None:
            aware = goal if self.goal_aware_entry else None
            name = self.entry.skill(obs, facts, self.motion, offsets, aware, self.planner)
            entry, node, facts = self.entry.bind(name, goal, facts, self.planner)
        result = self._plans(goal, node, facts, self.planner)
        return entry, list(result.actions), result

    def run_skill(
        self,
        env: SkillEnv,
        skill: SkillSpec | BoundSkill,
        obs: np.ndarray,
        tracker: TcpTracker | None = None,
        objects: ObjectTracker | None = None,
    ) -> tuple[SkillOutcome, np.ndarray]:
        """Run one option (``option.run_option``) with this executor's policy for it,
        telling its motion memory every command and ``on_step`` every env step."""
        bound = skill if isinstance(skill, BoundSkill) else BoundSkill(skill)
        return run_option(
            OptionRun(self.domain, self.policies[bound.skill.name], self.motion, self.on_step),
            env, bound, obs, tracker, objects,
        )  # fmt: skip

    def execute(
        self,
        goal: Iterable[str],
        env: SkillEnv,
        obs: np.ndarray,
        after_attempt: Callable[[int, ExecutionResult], Any] | None = None,
    ) -> ExecutionResult:
        """Reach ``goal`` from the env's current state (``obs`` is its latest observation),
        deciding from the percepts; ``success`` is what the robot believes (score an
        episode on the simulator's truth, e.g. ``env.facts()``, outside).

        ``after_attempt(attempt, result)``, if given, is called when an attempt's skill
        sequence has ended, before anything else moves: where an executor with
        ``max_replans = attempt`` would have stopped (Tables IV/V score every budget from
        one run this way)."""
        target = parse_goal(goal, self.domain)
        goal = target.atoms()
        _check_observation(obs, env)
        started = time.perf_counter()
        self.motion = MotionMemory()  # the arm is taken to be at rest
        facts = env.percept().facts
        result = ExecutionResult(goal=goal, success=False, entry_skill=None, plan=[])
        tracker = (
            None if self.filter_gain is None else TcpTracker(self.filter_gain, self.motion_model)
        )
        objects = ObjectTracker(self.domain, perception=env.perception)
        objects.update(env.percept())

        def reached(facts_now: Iterable[str], obs_now: np.ndarray) -> bool:
            return target.holds(self.domain, facts_now, obs_now, objects.offsets())

        planning_time = 0.0
        pursued = goal  # the goal, or the part of it within reach of what is perceived
        for attempt in range(self.max_replans + 1):
            if reached(facts, obs):
                result.success = True
                break
            if self.domain.hand_empty in facts and obs[7] != GRIPPER_OPEN_CMD:
                obs, result.failure = open_gripper(env)
                self.motion.still(GRIPPER_OPEN_STEPS)
                if result.failure:
                    if not is_divergence(result.failure):  # the env's episode is over
                        result.success = reached(env.percept().facts, env.observe())
                    break
            t0 = time.perf_counter()
            seen = obs if tracker is None else tracker.read(obs)
            entry, plan, planned = self.plan(pursued, seen, facts, objects.offsets())
            planning_time += time.perf_counter() - t0
            if attempt == 0:
                result.entry_skill = entry.split()[0] if entry else None
                result.plan = plan
            self._emit("plan", attempt=attempt, entry=entry, plan=plan)
            if not planned.solved:
                result.failure = f"no plan: unreachable goal facts {list(planned.unreached)}"
                within = [fact for fact in goal if fact not in set(planned.unreached)]
                if pursued != goal or len(within) in (0, len(goal)):
                    break
                if attempt >= self.max_replans:
                    break
                # part of the goal is out of reach from what is perceived (an object not
                # seen yet, say): pursue the rest, then look again and replan the whole
                if after_attempt is not None:
                    after_attempt(attempt, result)
                pursued = within
                result.replans += 1
                self._emit("replan", attempt=attempt + 1, failure=result.failure)
                continue
            entered = [entry] if entry else []
            obs, failed = self._run_sequence(env, entered + plan, obs, result, tracker, objects)
            facts = env.percept().facts
            if after_attempt is not None:
                after_attempt(attempt, result)
            if not failed:
                result.success = reached(facts, obs)
                if not result.success:
                    missing = target.missing(self.domain, facts, obs, objects.offsets())
                    result.failure = f"plan finished but goal facts {missing} missing"
                    if pursued != goal and attempt < self.max_replans:
                        pursued = goal  # the part within reach is done: replan the whole
                        result.replans += 1
                        self._emit("replan", attempt=attempt + 1, failure=result.failure)
                        continue
                break
            result.failure = failed
            pursued = goal
            if is_divergence(failed):
                break  # the world was reset: never replan
            if TIME_LIMIT in failed or EPISODE_ENDED in failed:
                result.success = reached(facts, obs)  # the env's episode is over: no replan
                break
            if attempt < self.max_replans:
                result.replans += 1
                self._emit("replan", attempt=attempt + 1, failure=failed)
        if result.success:
            result.failure = None
        self._emit("end", success=result.success, failure=result.failure, replans=result.replans)
        result.final_facts = sorted(facts)
        result.timings = {
            "planning_s": round(planning_time, 6),
            "total_s": round(time.perf_counter() - started, 4),
        }
        return result

    def _emit(self, kind: str, **fields: Any) -> None:
        """Tell ``on_event`` (if set) what just happened."""
        if self.on_event is not None:
            self.on_event(kind, fields)

    def _run_sequence(
        self,
        env: SkillEnv,
        sequence: list[str],
        obs: np.ndarray,
        result: ExecutionResult,
        tracker: TcpTracker | None,
        objects: ObjectTracker,
    ) -> tuple[np.ndarray, str | None]:
        """Run skills in order; stop at the first failure and return its reason."""
        for index, name in enumerate(sequence):
            bound = bind_step(self.domain.lifting, self.skills, name)
            skill = bound.skill
            target = node_position(self.domain.nodes, skill.end, bound.offsets(objects.offsets()))
            self._emit("skill", name=name, target=skill.end, position=target)
            outcome, obs = self.run_skill(env, bound, obs, tracker, objects)
            facts = env.percept().facts
            if outcome.success and not (skill.add_effects <= facts):
                outcome.success = False
                outcome.failure = f"expected effects {sorted(skill.add_effects - facts)} missing"
            result.outcomes.append(outcome)
            self._emit("outcome", **{k: getattr(outcome, k) for k in OUTCOME_EVENT})
            if not outcome.success:
                return obs, f"{name}: {outcome.failure}"
            if index < len(sequence) - 1 and env.episode_over:
                return obs, f"after {name}: {EPISODE_ENDED}"
            if self.reset_joints and index < len(sequence) - 1:
                try:
                    outcome.reset_steps = env.joint_reset()
                    self.motion.still(outcome.reset_steps)
                except SimulationError as err:
                    return obs, f"joint reset after {name}: {err}"
                if env.episode_over:
                    return obs, f"joint reset after {name}: {EPISODE_ENDED}"
                obs = env.observe()
                objects.update(env.percept())
                if tracker is not None:
                    tracker.settle()
        return obs, None


OUTCOME_EVENT = ("skill", "success", "steps", "failure")
"""The ``SkillOutcome`` fields an ``outcome`` event carries."""


def _check_observation(obs: Any, env: SkillEnv) -> None:
    """Refuse an observation that is not the env's: wrong shape or non-finite.

    Raises:
        ValueError: naming the shape expected and the one given.
    """
    space = getattr(env, "observation_space", None)
    expected = getattr(space, "shape", None)
    array = np.asarray(obs)
    if array.dtype.kind not in "iuf" or (expected is not None and array.shape != expected):
        raise ValueError(
            f"execute: obs must be the env's observation of shape {expected}, got shape "
            f"{array.shape} ({array.dtype})"
        )
    if not np.all(np.isfinite(array)):
        raise ValueError("execute: obs has non-finite values")


def load_executor(domain: Domain, directory: str | Path | None = None, **kwargs: Any) -> Executor:
    """An executor with the policies and classifier of ``directory`` (default: the domain's
    shipped defaults), planning over the success rates its manifest records."""
    from osg_control.execution.defaults import load_defaults

    defaults = load_defaults(domain, directory)
    kwargs.setdefault("motion_model", defaults.motion_model)
    return Executor(domain, defaults.policies, defaults.classifier, defaults.graph, **kwargs)
