"""Evaluation: the paper's Table I (skills under observation noise) and Tables IV/V (tasks).

Episodes run in parallel workers; episode ``i`` of a cell draws its start from
``SeedSequence([seed, cell, i])``, so the tables do not depend on the number of workers.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from osg_control.collect import LocalExecutor, run_scripted_episode
from osg_control.env import EnvConfig, KitchenEnv
from osg_control.skills import NODES, SKILLS, SKILLS_BY_NAME, get_skill

TASKS: dict[str, dict[str, Any]] = {
    "pick-up": {"goal": ["cube-lifted"], "door_opening": 0.0},
    "open-door": {"goal": ["door-open"], "door_opening": 0.0},
    "open+pick-up": {"goal": ["door-open", "cube-lifted"], "door_opening": 0.0},
    "pick-up+place": {"goal": ["cube-in-cabinet"], "door_opening": 0.40},
    "open+pick-up+place": {"goal": ["door-open", "cube-in-cabinet"], "door_opening": 0.0},
}
"""The paper's five tasks (Tables IV and V); pick-up+place starts with the door open."""
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
    from osg_control.policy import load_policies

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


def run_skill_episode(task: SkillEpisode) -> bool:
    """Run a learned skill from a random start in its initiation region; True on success."""
    skill = get_skill(task.skill)
    policy = _policies(task.policy_dir)[task.skill]
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
) -> dict[str, Any]:
    """Table I: success rate of every learned skill at each observation-noise level.

    Returns:
        ``{"noise": [...], "episodes": N, "rows": [{"skill", "rates": [...],
        "scripted": rate}]}``.
    """
    names = list(skills or SKILLS_BY_NAME)
    executor = LocalExecutor(workers)
    tasks = [
        SkillEpisode(name, str(policy_dir), float(noise), seed, cell, index)
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
    lines = [f"Table I: learned skill success ({table['episodes']} episodes per cell)", header]
    for i, row in enumerate(table["rows"], 1):
        rates = "".join(f" {r:10.3f}" for r in row["rates"])
        lines.append(f"{i:2d} {row['skill']:26s}{rates} {row['scripted']:9.2f}")
    return "\n".join(lines)
