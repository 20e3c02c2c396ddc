"""Where a learned skill's Table I episodes fail: the truth at the end of each failure.

Usage: ``python tools/skill_failures.py --skill pick-up-cube [--episodes N] [--seed S]
[--cell K] [--noise SIGMA] [--filter [GAIN]] [--warm-readings N] [--models DIR] [--workers W]
[--json]``.

Runs Table I's episodes of one skill (``evaluation.skill_table.run_skill_episode``'s starts:
episode ``i`` of cell ``K`` draws from ``evaluate.episode_rng``; ``osg eval-skills --noise A
B C`` runs its columns as cells 0, 1, 2), and prints, for each failure, the truth: the
steps run, the TCP's closest approach to and final offset from the end node, the world
facts at the end, the gripper command, and the error of the skill's frame (the object
tracker's estimate of its object's displacement minus the true one). The summary line
gives the success rate and the mean frame error of failed against succeeded episodes.

``--warm-readings N`` (with ``--filter``) first holds the arm still for N control steps at
its start, feeding the TCP filter those readings, as the executor's filter has read the
skills before a skill in a task; the skill then has its step budget less N. It tests
whether a failure comes from the filter's first estimate (one raw reading) rather than
the skill. Diagnosis only: nothing here decides, and Table I is unchanged.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass
from typing import Any

import numpy as np

from osg_control.commands import add_filter_argument
from osg_control.control.estimator import FilteredPolicy
from osg_control.domain.frames import in_skill_frame, skill_frame, skill_offset
from osg_control.domain.registry import get_domain
from osg_control.evaluation.evaluate import episode_rng
from osg_control.evaluation.skill_table import _env, _policy
from osg_control.execution.defaults import load_defaults
from osg_control.execution.objects import ObjectTracker
from osg_control.parallel import LocalExecutor
from osg_control.perception.spec import perception_spec

HOLD = np.zeros(7)
"""A control step that holds the arm and the gripper (relative actions; 0 keeps the latched
gripper command)."""


@dataclass(frozen=True)
class Probe:
    """One Table I episode to run and inspect."""

    domain: str
    skill: str
    models: str
    noise: float
    gain: float | None
    motion: tuple[float, float]
    seed: int
    cell: int
    index: int
    warm: int


def _frame_error(env: Any, domain: Any, skill: Any, offset: np.ndarray) -> float | None:
    """|estimated - true| displacement of the skill's frame [m] (None: no object frame)."""
    frame = skill_frame(domain, skill)
    if frame is None:
        return None
    truth = np.asarray(env.anchor_offsets.get(frame, np.zeros(3)))
    return round(float(np.linalg.norm(offset - truth)), 4)


def probe(task: Probe) -> dict[str, Any]:
    """Run one episode as Table I does and read the truth along it."""
    domain = get_domain(task.domain)
    skill = domain.skill(task.skill)
    policy: Any = _policy(task.domain, task.models, task.skill)
    if task.gain is not None:
        policy = FilteredPolicy(policy, task.gain, task.motion)
    env = _env(task.domain, task.skill, perception_spec("paper", task.noise))
    rng = episode_rng(task.seed, task.skill, task.cell, task.index)
    options = {"radius": skill.start_radius, "angle": skill.start_angle}
    obs, _ = env.reset(seed=int(rng.integers(2**31)), options=options)
    objects = ObjectTracker(domain, perception=env.perception)
    objects.update(env.percept())
    end = np.asarray(env.node_position(skill.end))
    closest, info, steps, gripper = np.inf, {"success": False}, 0, 0.0
    for _ in range(task.warm):  # only with a filter (main refuses it without)
        policy.tracker.read(obs)
        obs, _reward, terminated, truncated, info = env.step(HOLD)
        policy.tracker.acted(HOLD)
        objects.update(env.percept())
        steps += 1
        if terminated or truncated:
            break
    offset = skill_offset(domain, skill, objects.offsets())
    while not env.episode_over and steps < skill.max_steps:
        offset = skill_offset(domain, skill, objects.offsets())
        action = policy(in_skill_frame(obs, offset))
        obs, _reward, _terminated, _truncated, info = env.step(action)
        objects.update(env.percept())
        steps += 1
        gripper = float(action[6])
        closest = min(closest, float(np.linalg.norm(env.tcp_pose()[0] - end)))
    final = env.tcp_pose()[0] - end
    return {
        "index": task.index,
        "success": bool(info["success"]),
        "steps": steps,
        "closest": round(closest, 4),
        "final_offset": np.round(final, 4).tolist(),
        "gripper_action": round(gripper, 2),
        "facts": sorted(env.facts()),
        "frame_error": _frame_error(env, domain, skill, offset),
    }


def _mean(values: list[float | None]) -> float | None:
    found = [v for v in values if v is not None]
    return round(float(np.mean(found)), 4) if found else None


def main() -> None:
    """Run the episodes and print every failure (``--json``: one object)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skill", required=True)
    parser.add_argument("--domain", default="kitchen")
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--cell", type=int, default=0, help="Table I column's cell (default 0)")
    parser.add_argument("--noise", type=float, default=0.02, help="TCP noise [m] (0.02)")
    add_filter_argument(parser)
    parser.add_argument("--warm-readings", type=int, default=0)
    parser.add_argument("--models", default=None, help="default: the shipped skills")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.episodes < 1 or args.warm_readings < 0 or args.workers < 1:
        parser.error("--episodes and --workers must be >= 1, --warm-readings >= 0")
    if args.warm_readings and args.filter is None:
        parser.error("--warm-readings warms the TCP filter: give --filter too")
    domain = get_domain(args.domain)
    domain.skill(args.skill)
    defaults = load_defaults(domain)
    models = args.models or str(defaults.directory / "skills")
    jobs = [
        Probe(
            domain.name,
            args.skill,
            models,
            args.noise,
            args.filter,
            defaults.motion_model,
            args.seed,
            args.cell,
            i,
            args.warm_readings,
        )  # fmt: skip
        for i in range(args.episodes)
    ]
    results = list(LocalExecutor(args.workers).map(probe, jobs))
    failures = [r for r in results if not r["success"]]
    summary = {
        "skill": args.skill,
        "episodes": args.episodes,
        "seed": args.seed,
        "cell": args.cell,
        "noise": args.noise,
        "filter_gain": args.filter,
        "warm_readings": args.warm_readings,
        "success": 1.0 - len(failures) / len(results),
        "frame_error_failed": _mean([r["frame_error"] for r in failures]),
        "frame_error_succeeded": _mean([r["frame_error"] for r in results if r["success"]]),
    }
    if args.json:
        print(json.dumps({**summary, "failures": failures}, indent=2))
        return
    for failure in failures:
        print(json.dumps(failure))
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
