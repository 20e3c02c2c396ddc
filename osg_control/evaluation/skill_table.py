"""The paper's Table I: every learned skill from random starts in its initiation region, at
each observation-noise level (and its scripted data's success beside it).

Episode ``i`` of skill ``N`` at noise level ``k`` draws from
``SeedSequence([skill_seed(seed, N), k, i])`` (``evaluate.episode_rng``): the table depends
neither on the number of workers nor on the other skills.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from osg_control.control.estimator import MOTION_MODEL, FilteredPolicy
from osg_control.data.collect import placed_start_options, run_scripted_episode
from osg_control.domain.base import Domain
from osg_control.domain.contract import SkillEnv
from osg_control.domain.frames import in_skill_frame, sample_placements, skill_offset
from osg_control.domain.registry import get_domain
from osg_control.environment.config import EnvConfig
from osg_control.evaluation.evaluate import cell_means, episode_rng
from osg_control.execution.objects import ObjectTracker
from osg_control.learning.checkpoints import require_skills
from osg_control.parallel import LocalExecutor, TaskExecutor
from osg_control.parallel.lazy import grid
from osg_control.perception.spec import PerceptionSpec


@cache
def _policy(domain: str, directory: str, skill: str) -> Any:
    """A skill's policy, loaded once per worker and checked against its domain."""
    from osg_control.execution.defaults import load_skill_policies

    return load_skill_policies(get_domain(domain), directory, [skill])[skill]


@cache
def _env(domain: str, skill: str, perception: PerceptionSpec) -> SkillEnv:
    found = get_domain(domain)
    return found.make_env(skill=found.skill(skill), config=EnvConfig(perception=perception))


@dataclass(frozen=True)
class SkillEpisode:
    """One learned-skill evaluation episode."""

    domain: str
    skill: str
    policy_dir: str
    perception: PerceptionSpec
    seed: int
    cell: int
    index: int
    filter_gain: float | None = None
    randomize: bool = False
    filter_motion: tuple[float, float] = MOTION_MODEL


def run_skill_episode(task: SkillEpisode) -> bool:
    """Run a learned skill from a random start in its initiation region (the domain's
    objects placed at random in their regions with ``randomize``); True on success, scored
    by the env on the simulator's truth. The policy sees the percept, in the skill's frame
    (the objects where the robot perceives them, ``ObjectTracker``)."""
    domain = get_domain(task.domain)
    skill = domain.skill(task.skill)
    policy: Callable[[np.ndarray], np.ndarray] = _policy(task.domain, task.policy_dir, task.skill)
    if task.filter_gain is not None:
        policy = FilteredPolicy(policy, task.filter_gain, task.filter_motion)
    env = _env(task.domain, task.skill, task.perception)
    rng = episode_rng(task.seed, task.skill, task.cell, task.index)
    reset_seed = int(rng.integers(2**31))
    options: dict[str, Any] = {"radius": skill.start_radius, "angle": skill.start_angle}
    if task.randomize:
        options = placed_start_options(domain, env, skill, sample_placements(domain, rng))
    obs, _ = env.reset(seed=reset_seed, options=options)
    objects = ObjectTracker(domain, perception=env.perception)
    objects.update(env.percept())
    for _ in range(skill.max_steps):
        offset = skill_offset(domain, skill, objects.offsets())
        obs, _reward, terminated, truncated, info = env.step(policy(in_skill_frame(obs, offset)))
        objects.update(env.percept())
        if terminated or truncated:
            return bool(info["success"])
    return False


def _scripted_success(task: tuple[str, str, int, int]) -> bool:
    domain = get_domain(task[0])
    return run_scripted_episode(domain, domain.skill(task[1]), task[2], task[3]).success


def learned_rates(
    domain: Domain,
    policy_dir: str | Path,
    names: Sequence[str],
    noise_levels: Sequence[float],
    episodes: int,
    seed: int = 0,
    executor: TaskExecutor | None = None,
    perception: PerceptionSpec | None = None,
    filter_gain: float | None = None,
    randomize: bool = False,
    filter_motion: tuple[float, float] = MOTION_MODEL,
    first_cell: int = 0,
    progress: bool = False,
) -> np.ndarray:
    """The success rate of each learned skill at each noise level, (skills, levels).

    Noise level ``k`` draws its episodes as cell ``first_cell + k`` (``episode_rng``):
    Table I's columns are cells 0, 1, ...; a check on other episodes (training's held-out
    checks) starts elsewhere. See ``skill_table`` for the other arguments.

    Raises:
        CheckpointError: a skill checkpoint missing.
    """
    require_skills(policy_dir, names)
    executor = executor or LocalExecutor(1)
    perception = perception or PerceptionSpec()
    cells = [(name, k, float(noise)) for name in names for k, noise in enumerate(noise_levels)]

    def job(cell: tuple[str, int, float], i: int) -> SkillEpisode:
        name, k, noise = cell
        seen = replace(perception, tcp_noise=noise)  # Table I's column k
        return SkillEpisode(
            domain.ref, name, str(policy_dir), seen, seed, first_cell + k, i, filter_gain,
            randomize, filter_motion,
        )  # fmt: skip

    outcomes = executor.map(run_skill_episode, grid(cells, episodes, job))
    rates = cell_means(outcomes, len(cells), episodes, "learned", progress)
    return rates.reshape(len(names), len(noise_levels))


def skill_table(
    domain: Domain,
    policy_dir: str | Path,
    noise_levels: Sequence[float] = (0.0, 0.01, 0.02),
    episodes: int = 200,
    seed: int = 0,
    workers: int = 2,
    skills: Sequence[str] | None = None,
    scripted_episodes: int = 100,
    filter_gain: float | None = None,
    executor: TaskExecutor | None = None,
    progress: bool = False,
    perception: PerceptionSpec | None = None,
    randomize: bool = False,
    filter_motion: tuple[float, float] = MOTION_MODEL,
) -> dict[str, Any]:
    """Table I: success rate of every learned skill at each observation-noise level.

    Args:
        randomize: place the domain's objects at random in their regions (else where the
            scene has them, the paper's protocol).
        filter_motion: the TCP filter's motion model (the domain's fit).
        noise_levels: the paper's TCP noise [m] of each column, added to ``perception``'s
            (default: the paper's protocol).
        filter_gain: run the policies on ``estimator.TcpFilter`` estimates with this gain;
            None (the paper's protocol) feeds them the raw noisy observation.
        executor: where the episodes run (default: a local pool of ``workers``).
        progress: show progress bars on stderr.

    Returns:
        ``{"noise": [...], "episodes": N, "filter_gain": g, "rows": [{"skill",
        "rates": [...], "scripted": rate}]}``.
    """
    names = list(skills or domain.skills_by_name)
    for name in names:
        domain.skill(name)
    executor = executor or LocalExecutor(workers)
    perception = perception or PerceptionSpec()
    rates = learned_rates(
        domain, policy_dir, names, noise_levels, episodes, seed, executor, perception,
        filter_gain, randomize, filter_motion, progress=progress,
    )  # fmt: skip
    scripted_tasks = grid(names, scripted_episodes, lambda n, i: (domain.ref, n, seed + 1, i))
    scripted = executor.map(_scripted_success, scripted_tasks)
    scripted_rates = cell_means(scripted, len(names), scripted_episodes, "scripted", progress)
    return {
        "noise": list(noise_levels),
        "perception": perception.to_dict(),
        "randomized_objects": randomize,
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
