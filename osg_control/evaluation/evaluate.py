"""Evaluation: the paper's Table I (skills under observation noise) and Tables IV/V (tasks).

Episodes run in parallel workers; episode ``i`` of a cell draws its start from
``SeedSequence([seed, cell, i])``, so the tables do not depend on the number of workers.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from osg_control.control.estimator import FilteredPolicy
from osg_control.data.collect import LocalExecutor, run_scripted_episode
from osg_control.evaluation.resume import resumable_map
from osg_control.kitchen.env import EnvConfig, KitchenEnv
from osg_control.kitchen.skills import NODES, SKILLS, SKILLS_BY_NAME, get_skill, nearest_start
from osg_control.kitchen.tasks import TASKS_BY_NAME, get_task

START_NODES: tuple[str, ...] = ("home", "above-cube", "door-front", "cabinet-front")


def start_regions() -> list[tuple[str, tuple[float, float, float]]]:
    """The 8 start states: the 4 movement-skill endpoints and the midpoints of the 4 longest
    movement edges (far from every node), as in the paper's Table III."""
    regions = [(name, NODES[name].position) for name in START_NODES]
    edges = sorted(
        {tuple(sorted((s.start, s.end))) for s in SKILLS if s.kind == "movement"},
        key=lambda e: -np.linalg.norm(np.subtract(NODES[e[0]].position, NODES[e[1]].position)),
    )
    for a, b in edges[:4]:
        mid = tuple((np.asarray(NODES[a].position) + NODES[b].position) / 2)
        regions.append((f"mid({a},{b})", (float(mid[0]), float(mid[1]), float(mid[2]))))
    return regions


@cache
def _policies(directory: str) -> dict[str, Any]:
    from osg_control.learning.policy import load_policies

    return load_policies(directory)


@cache
def _env(skill: str, noise: float) -> KitchenEnv:
    return KitchenEnv(skill=skill, config=EnvConfig(obs_noise_std=noise))


@dataclass(frozen=True)
class SkillEpisode:
    """One learned-skill evaluation episode."""

    skill: str
    policy_dir: str
    noise: float
    seed: int
    cell: int
    index: int
    filter_gain: float | None = None


def run_skill_episode(task: SkillEpisode) -> bool:
    """Run a learned skill from a random start in its initiation region; True on success."""
    skill = get_skill(task.skill)
    policy: Callable[[np.ndarray], np.ndarray] = _policies(task.policy_dir)[task.skill]
    if task.filter_gain is not None:
        policy = FilteredPolicy(policy, task.filter_gain)
    env = _env(task.skill, task.noise)
    rng = np.random.default_rng(np.random.SeedSequence([task.seed, task.cell, task.index]))
    obs, _ = env.reset(
        seed=int(rng.integers(2**31)),
        options={"radius": skill.start_radius, "angle": skill.start_angle},
    )
    for _ in range(skill.max_steps):
        obs, _reward, terminated, truncated, info = env.step(policy(obs))
        if terminated or truncated:
            return bool(info["success"])
    return False


def _scripted_success(task: tuple[str, int, int]) -> bool:
    return run_scripted_episode(get_skill(task[0]), task[1], task[2]).success


def skill_table(
    policy_dir: str | Path,
    noise_levels: Sequence[float] = (0.0, 0.01, 0.02),
    episodes: int = 200,
    seed: int = 0,
    workers: int = 2,
    skills: Sequence[str] | None = None,
    scripted_episodes: int = 100,
    filter_gain: float | None = None,
) -> dict[str, Any]:
    """Table I: success rate of every learned skill at each observation-noise level.

    Args:
        filter_gain: run the policies on ``estimator.TcpFilter`` estimates with this gain;
            None (the paper's protocol) feeds them the raw noisy observation.

    Returns:
        ``{"noise": [...], "episodes": N, "filter_gain": g, "rows": [{"skill",
        "rates": [...], "scripted": rate}]}``.
    """
    names = list(skills or SKILLS_BY_NAME)
    executor = LocalExecutor(workers)
    tasks = [
        SkillEpisode(name, str(policy_dir), float(noise), seed, cell, index, filter_gain)
        for cell, (name, noise) in enumerate((n, s) for n in names for s in noise_levels)
        for index in range(episodes)
    ]
    outcomes = np.array(list(executor.map(run_skill_episode, tasks)), dtype=float)
    rates = outcomes.reshape(len(names), len(noise_levels), episodes).mean(axis=2)
    scripted_tasks = [(n, seed + 1, i) for n in names for i in range(scripted_episodes)]
    scripted = np.array(list(executor.map(_scripted_success, scripted_tasks)), dtype=float)
    scripted_rates = scripted.reshape(len(names), scripted_episodes).mean(axis=1)
    return {
        "noise": list(noise_levels),
        "episodes": episodes,
        "seed": seed,
        "filter_gain": filter_gain,
        "rows": [
            {"skill": n, "rates": rates[i].tolist(), "scripted": float(scripted_rates[i])}
            for i, n in enumerate(names)
        ],
    }


def format_skill_table(table: dict[str, Any]) -> str:
    """Table I as text."""
    header = (
        f"{'#':>2} {'skill':26s}"
        + "".join(f" {'sigma=' + format(n, 'g'):>10s}" for n in table["noise"])
        + f" {'scripted':>9s}"
    )
    observed = (
        "raw observations"
        if table.get("filter_gain") is None
        else f"TCP filter gain {table['filter_gain']:g}"
    )
    lines = [
        f"Table I: learned skill success ({table['episodes']} episodes per cell, {observed})",
        header,
    ]
    for i, row in enumerate(table["rows"], 1):
        rates = "".join(f" {r:10.3f}" for r in row["rates"])
        lines.append(f"{i:2d} {row['skill']:26s}{rates} {row['scripted']:9.2f}")
    return "\n".join(lines)


@cache
def _executor(models: str | None, max_replans: int, filter_gain: float | None) -> Any:
    from osg_control.execution.executor import load_executor

    return load_executor(models, max_replans=max_replans, filter_gain=filter_gain)


@cache
def _plain_env(noise: float) -> KitchenEnv:
    return KitchenEnv(config=EnvConfig(obs_noise_std=noise))


@dataclass(frozen=True)
class StartEpisode:
    """One episode from a random start in one of the 8 start regions."""

    models: str | None
    region: int
    noise: float
    seed: int
    cell: int
    index: int


def _reset_in_region(env: KitchenEnv, task: StartEpisode, door: float = 0.0) -> np.ndarray:
    rng = np.random.default_rng(np.random.SeedSequence([task.seed, task.cell, task.index]))
    _name, position = start_regions()[task.region]
    obs, _ = env.reset(
        seed=int(rng.integers(2**31)),
        options={
            "position": position,
            "radius": 0.15,
            "angle": 0.2,
            "gripper": "open",
            "world": {"door_opening": door},
        },
    )
    return obs


def run_reach_episode(task: StartEpisode) -> tuple[bool, bool, bool]:
    """Table III: classify a random start, run the chosen movement skill.

    Returns:
        (success, whether the start lay outside the chosen skill's initiation region,
        success of the nearest-start-node baseline from the same start).
    """
    executor = _executor(task.models, 0, None)
    env = _plain_env(task.noise)
    outcomes = []
    outside = False
    for chooser in ("classifier", "nearest"):
        # Door open: every movement skill's path is then clear of the handle.
        obs = _reset_in_region(env, task, door=0.40)
        if chooser == "classifier":
            name = str(executor.classifier.predict(obs))
            skill = SKILLS_BY_NAME[name]
            distance = np.linalg.norm(env.tcp_pose()[0] - np.asarray(skill.start_node.position))
            outside = bool(distance > skill.start_radius)
        else:
            name = nearest_start_skill(env.tcp_pose()[0])
        outcome, _ = executor.run_skill(env, SKILLS_BY_NAME[name], obs)
        outcomes.append(outcome.success)
    return outcomes[0], outside, outcomes[1]


def nearest_start_skill(position: np.ndarray) -> str:
    """The movement skill whose start node is nearest to a TCP position (the baseline)."""
    return nearest_start((s for s in SKILLS if s.kind == "movement"), position).name


def reach_table(
    models: str | None = None,
    episodes: int = 200,
    seed: int = 0,
    workers: int = 2,
    noise: float = 0.0,
) -> dict[str, Any]:
    """Table III: entry-skill success from random starts around the 8 start regions."""
    regions = start_regions()
    tasks = [
        StartEpisode(models, r, noise, seed, r, i)
        for r in range(len(regions))
        for i in range(episodes)
    ]
    results = np.array(list(LocalExecutor(workers).map(run_reach_episode, tasks)), dtype=float)
    results = results.reshape(len(regions), episodes, 3).mean(axis=1)
    rows = [
        {"start": name, "success": r[0], "outside_initiation": r[1], "nearest_node_success": r[2]}
        for (name, _), r in zip(regions, results.tolist(), strict=True)
    ]
    return {
        "episodes": episodes,
        "seed": seed,
        "noise": noise,
        "rows": rows,
        "average": float(results[:, 0].mean()),
        "nearest_node_average": float(results[:, 2].mean()),
    }


def format_reach_table(table: dict[str, Any]) -> str:
    """Table III as text."""
    lines = [
        f"Table III: reaching the graph from random starts ({table['episodes']} episodes each)",
        f"{'#':>2} {'start region':34s} {'success':>8s} {'outside I':>10s} {'nearest-node':>13s}",
    ]
    for i, row in enumerate(table["rows"], 1):
        lines.append(
            f"{i:2d} {row['start']:34s} {row['success']:8.3f} {row['outside_initiation']:10.3f} "
            f"{row['nearest_node_success']:13.3f}"
        )
    lines.append(
        f"   {'average':34s} {table['average']:8.3f} {'':10s} {table['nearest_node_average']:13.3f}"
    )
    return "\n".join(lines)


@dataclass(frozen=True)
class TaskEpisode:
    """One full-pipeline episode of a task from a start region."""

    start: StartEpisode
    task: str
    max_replans: int
    filter_gain: float | None = None


def run_task_episode(episode: TaskEpisode) -> bool:
    """Tables IV/V: run the executor on a task from a random start; True on success."""
    task = get_task(episode.task)
    env = _plain_env(episode.start.noise)
    obs = _reset_in_region(env, episode.start, door=task.door_opening)
    executor = _executor(episode.start.models, episode.max_replans, episode.filter_gain)
    return bool(executor.execute(task.goal, env, obs).success)


def task_table(
    models: str | None = None,
    episodes: int = 100,
    seed: int = 0,
    workers: int = 2,
    noise: float = 0.02,
    tasks: Sequence[str] = tuple(TASKS_BY_NAME),
    replans: Sequence[int] = (0, 2),
    filter_gain: float | None = None,
    resume_dir: Path | None = None,
) -> dict[str, Any]:
    """Tables IV and V: task success per start region, without and with replanning.

    ``filter_gain``: the executor's ``TcpFilter`` gain (None: raw observations).
    ``resume_dir``: keep finished episodes there and resume from them (``resume``).
    """
    regions = start_regions()
    cells = [(t, r, k) for k in replans for t in tasks for r in range(len(regions))]
    jobs = [
        TaskEpisode(StartEpisode(models, r, noise, seed, 100 + ti * 10 + r, i), t, k, filter_gain)
        for (t, r, k) in cells
        for ti in [list(tasks).index(t)]
        for i in range(episodes)
    ]
    results = resumable_map(LocalExecutor(workers), run_task_episode, jobs, resume_dir)
    outcomes = np.array(results, dtype=float)
    rates = outcomes.reshape(len(replans), len(tasks), len(regions), episodes).mean(axis=3)
    return {
        "episodes": episodes,
        "seed": seed,
        "noise": noise,
        "filter_gain": filter_gain,
        "regions": [name for name, _ in regions],
        "tasks": list(tasks),
        "replans": list(replans),
        "rates": rates.tolist(),
        "averages": rates.mean(axis=2).tolist(),
    }


def format_task_table(table: dict[str, Any]) -> str:
    """Tables IV and V as text, one block per replanning budget."""
    lines = []
    for k, budget in enumerate(table["replans"]):
        lines.append(
            f"Tables IV/V: task success, sigma = {table['noise']:g} m, max replans = {budget} "
            f"({table['episodes']} episodes per cell)"
        )
        lines.append(
            f"{'#':>2} {'start region':34s}" + "".join(f" {t:>19s}" for t in table["tasks"])
        )
        for r, region in enumerate(table["regions"]):
            values = "".join(
                f" {table['rates'][k][t][r]:19.3f}" for t in range(len(table["tasks"]))
            )
            lines.append(f"{r + 1:2d} {region:34s}{values}")
        averages = "".join(f" {v:19.3f}" for v in table["averages"][k])
        lines.append(f"   {'average':34s}{averages}")
        lines.append("")
    return "\n".join(lines)
