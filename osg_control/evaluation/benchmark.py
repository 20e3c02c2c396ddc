"""``osg evaluate benchmark``: a domain's outside benchmark (``Domain.benchmark``), scored
by the env's own completion report.

Each episode starts from the env's own reset (or, with ``perturbed``, from a random start
in the domain's first start region, the drive there not counted), plans for the goal set's
facts, executes within the env's step limit (or without one), and scores
``points * (tasks the env reports completed) / (tasks in the goal set)``. The score's
interval is the Wilson score interval of the mean completed fraction: a fraction in [0, 1]
has at most the variance of a Bernoulli variable of the same mean, so the interval is
conservative, and it stays informative when every episode scores the same.

Episode ``i`` resets with a seed drawn from ``SeedSequence([skill_seed(seed, goal set), 0,
i])``: the same starts for every variant, whatever the number of workers.

What the executor perceives is a named perception (``perception.spec``), by default the
domain's first (``Domain.perceptions``; e.g. ``env``, an outside env's own observation);
``sim`` is the simulator's state, an oracle, and is reported as one.
"""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from osg_control.domain.base import Domain
from osg_control.domain.benchmark import Benchmark
from osg_control.domain.registry import get_domain
from osg_control.errors import DomainError, UsageError
from osg_control.evaluation.check import wilson_interval
from osg_control.evaluation.evaluate import cached_executor, episode_rng
from osg_control.evaluation.resume import resumable_map, stored_count
from osg_control.parallel import LocalExecutor, TaskExecutor
from osg_control.perception.spec import PERCEPTIONS, PerceptionSpec, check_supported

Z95 = 1.96
"""Two-sided 95 % normal quantile of the score's interval."""
START_STEPS = 40
"""Steps a perturbed start may take to drive from the env's reset to its random pose."""


def benchmark_of(domain: Domain) -> Benchmark:
    """The domain's benchmark.

    Raises:
        DomainError: the domain has none.
    """
    if domain.benchmark is None:
        raise DomainError(f"domain {domain.name!r} has no outside benchmark")
    return domain.benchmark


@dataclass(frozen=True)
class BenchmarkEpisode:
    """One benchmark episode: a goal set's tasks under one protocol variant."""

    domain: str
    models: str | None
    goal_set: str
    tasks: tuple[str, ...]
    seed: int
    index: int
    perception: PerceptionSpec | None = None
    filter_gain: float | None = None
    perturbed: bool = False
    limited: bool = True
    max_replans: int = 2
    env_kwargs: str = ""
    """The env's own constructor options, as JSON ("" for none)."""


def benchmark_perception(
    domain: Domain, perception: PerceptionSpec | None = None, noise: float = 0.0
) -> PerceptionSpec:
    """The perception a benchmark runs on: ``perception``, default the domain's first
    (``Domain.perceptions``), with the paper's TCP ``noise`` [m] if given.

    Raises:
        UsageError: a perception the domain does not support, or noise on ``sim``.
    """
    supported = tuple(domain.perceptions)
    spec = perception or PerceptionSpec(supported[0])
    check_supported(spec, supported, domain.name)
    if noise:
        if spec.name == "sim":
            raise UsageError("the sim perception is the simulator's exact state: no --noise")
        spec = replace(spec, tcp_noise=noise)
    return spec


@cache
def _benchmark_env(
    domain: str,
    tasks: tuple[str, ...],
    limit: int | None,
    perception: PerceptionSpec | None,
    start_steps: int,
    env_kwargs: str = "",
) -> Any:
    spec = benchmark_perception(get_domain(domain), perception)
    extra = {"env_kwargs": env_kwargs} if env_kwargs else {}
    return benchmark_of(get_domain(domain)).make_env(
        tasks, limit, 0.0, start_steps, perception=spec, **extra
    )


def run_benchmark_episode(episode: BenchmarkEpisode) -> dict[str, Any]:
    """Run one episode; returns the tasks the env reports completed, the steps used (from
    the start) and the executor's failure, if any."""
    domain = get_domain(episode.domain)
    bench = benchmark_of(domain)
    limit = bench.step_limit if episode.limited else None
    start_steps = START_STEPS if episode.perturbed else 0
    env = _benchmark_env(
        episode.domain, episode.tasks, limit, episode.perception, start_steps, episode.env_kwargs
    )
    rng = episode_rng(episode.seed, episode.goal_set, 0, episode.index)
    options = None
    if episode.perturbed:
        region = domain.start_regions[0]
        options = {
            "position": region.position,
            "radius": region.radius,
            "angle": region.angle,
            "max_steps": START_STEPS,
        }
    obs, _ = env.reset(seed=int(rng.integers(2**31)), options=options)
    executor = cached_executor(
        episode.domain, episode.models, episode.max_replans, episode.filter_gain
    )
    result = executor.execute(bench.goal(episode.tasks), env, obs)
    completed = sorted(set(env.completed_tasks()) & set(episode.tasks))
    return {"completed": completed, "steps": int(env.steps), "failure": result.failure}


def check_benchmark_result(episode: BenchmarkEpisode, result: Any) -> None:
    """Whether ``result`` can be ``run_benchmark_episode(episode)``'s (a resumed chunk's):
    exactly its three keys, ``completed`` sorted distinct names of the episode's tasks,
    ``steps`` a whole number, ``failure`` null or text.

    Raises:
        ValueError: naming the key and the value that cannot be.
    """
    if not isinstance(result, dict) or set(result) != {"completed", "steps", "failure"}:
        raise ValueError(f"expected completed, steps and failure, got {result!r}")
    done = result["completed"]
    if not isinstance(done, list) or not all(isinstance(t, str) for t in done):
        raise ValueError(f"completed must be a list of task names, got {done!r}")
    if done != sorted(set(done)) or not set(done) <= set(episode.tasks):
        raise ValueError(f"completed must be distinct tasks of {list(episode.tasks)}, got {done}")
    stored_count(result["steps"], "steps")
    if not (result["failure"] is None or isinstance(result["failure"], str)):
        raise ValueError(f"failure must be null or text, got {result['failure']!r}")


def score_interval(fractions: np.ndarray, points: float, z: float = Z95) -> tuple[float, float]:
    """The Wilson interval of the mean completed fraction, in points (see module doc)."""
    low, high = wilson_interval(float(np.mean(fractions)), len(fractions), z)
    return points * low, points * high


def run_benchmark(
    domain: Domain,
    goal_set: str | None = None,
    tasks: Sequence[str] | None = None,
    episodes: int = 100,
    seed: int = 0,
    models: str | None = None,
    noise: float = 0.0,
    filter_gain: float | None = None,
    perturbed: bool = False,
    limited: bool = True,
    max_replans: int = 2,
    workers: int = 2,
    executor: TaskExecutor | None = None,
    resume_dir: Path | None = None,
    perception: PerceptionSpec | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Score the domain's policies on its benchmark (see module doc).

    ``goal_set`` names one of the benchmark's sets (default: its ``default_set``);
    ``tasks`` (the env's task names) overrides it. ``perception``: what the executor
    perceives (default: the domain's first, see ``benchmark_perception``), with the paper's
    TCP ``noise`` [m] if given; ``env_kwargs``: the env's own constructor options (e.g.
    FrankaKitchen-v1's ``robot_noise_ratio``). Returns a JSON-ready summary: ``score`` (the
    mean, 0 to ``points``), ``interval`` (95 %), ``perception`` (its name and noise),
    ``task_rates`` (each task's completion rate), ``full_rate`` (episodes completing every
    task), ``max_steps`` (the largest step count of any episode), ``steps`` (mean and max)
    and the protocol.

    Raises:
        DomainError: no benchmark, an unknown goal set or task.
        UsageError: a perception the domain does not support.
    """
    bench = benchmark_of(domain)
    spec = benchmark_perception(domain, perception, noise)
    kwargs_json = json.dumps(dict(env_kwargs), sort_keys=True) if env_kwargs else ""
    if tasks:
        chosen = bench.check_tasks(tuple(tasks))
        name = "+".join(chosen)
    else:
        name = goal_set or bench.default_set
        chosen = bench.tasks_of(name)
    jobs = [
        BenchmarkEpisode(
            domain.ref,
            models,
            name,
            chosen,
            seed,
            i,
            spec,
            filter_gain,
            perturbed,
            limited,
            max_replans,
            kwargs_json,
        )
        for i in range(episodes)
    ]
    results = resumable_map(
        executor or LocalExecutor(workers),
        run_benchmark_episode,
        jobs,
        resume_dir,
        check_benchmark_result,
    )
    done = np.array([[t in r["completed"] for t in chosen] for r in results], dtype=float)
    fractions = done.mean(axis=1)
    steps = np.array([r["steps"] for r in results])
    failures = Counter(r["failure"] for r in results if r["failure"])
    low, high = score_interval(fractions, bench.points)
    return {
        "benchmark": bench.name,
        "goal_set": name,
        "tasks": list(chosen),
        "episodes": episodes,
        "seed": seed,
        "score": round(float(bench.points * fractions.mean()), 3),
        "interval": [round(low, 3), round(high, 3)],
        "confidence": 0.95,
        "perception": spec.to_dict(),
        "oracle": spec.name == "sim",
        "max_steps": int(steps.max()),
        "full_rate": float((fractions == 1.0).mean()),
        "task_rates": {t: float(done[:, k].mean()) for k, t in enumerate(chosen)},
        "steps": {"mean": float(steps.mean()), "max": int(steps.max())},
        "step_limit": bench.step_limit if limited else None,
        "perturbed": perturbed,
        "noise": spec.tcp_noise,
        "env_kwargs": dict(env_kwargs or {}),
        "filter_gain": filter_gain,
        "max_replans": max_replans,
        "failures": dict(failures.most_common()),
        "published": {
            method: scores[name] for method, scores in bench.published.items() if name in scores
        },
        "published_note": bench.published_note,
    }


def format_benchmark(summary: dict[str, Any]) -> str:
    """A benchmark summary as text."""
    limit = summary["step_limit"]
    protocol = [
        f"step limit {limit}" if limit else "no step limit",
        "perturbed starts" if summary["perturbed"] else "the env's reset",
        f"noise {summary['noise']:g} m" + (" + filter" if summary["filter_gain"] else ""),
    ]
    low, high = summary["interval"]
    perception = summary.get("perception")
    if perception:
        name = perception["name"]
        label = "ORACLE: " if name == "sim" else ""
        protocol.insert(0, f"perception {name} ({label}{PERCEPTIONS.get(name, '')})")
    if summary.get("env_kwargs"):
        protocol.append(f"env options {json.dumps(summary['env_kwargs'], sort_keys=True)}")
    lines = [
        f"{summary['benchmark']}: {summary['goal_set']} ({', '.join(summary['tasks'])})",
        f"  protocol: {'; '.join(protocol)}; {summary['episodes']} episodes, seed "
        f"{summary['seed']}",
        f"  score {summary['score']:.1f}  (95 % interval {low:.1f}-{high:.1f}); all tasks "
        f"done in {summary['full_rate']:.1%} of episodes",
        f"  steps used: mean {summary['steps']['mean']:.0f}, max {summary['steps']['max']}",
    ]
    lines += [f"  {task:16s} {rate:.3f}" for task, rate in summary["task_rates"].items()]
    for failure, count in list(summary["failures"].items())[:5]:
        lines.append(f"  failure x{count}: {failure}")
    if summary.get("published"):
        scores = ", ".join(f"{m} {s:g}" for m, s in summary["published"].items())
        lines.append(f"  published on {summary['goal_set']}: {scores}")
        lines.append(f"    ({summary['published_note']})")
    return "\n".join(lines)
