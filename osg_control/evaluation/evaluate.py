"""Evaluation: the paper's Table III (reaching the graph) and Tables IV/V (tasks), for any
domain, and what every table shares (Table I: ``skill_table``).

Episodes run in parallel workers; episode ``i`` of a cell draws its start from
``SeedSequence([skill_seed(seed, NAME), k, i])`` where NAME is the cell's skill or task and
``k`` its noise level or start region, so the tables depend neither on the number of
workers nor on which other skills or tasks a domain has. Workers find the domain by name
(``osg_control.domain.registry``). Episodes are made on demand (``parallel.lazy.grid``) and
their outcomes summed per cell as they arrive, so memory does not grow with the number of
episodes.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from osg_control.domain.base import Domain
from osg_control.domain.contract import SkillEnv
from osg_control.domain.frames import sample_placements
from osg_control.domain.registry import get_domain
from osg_control.domain.spec import nearest_start
from osg_control.evaluation.resume import resumable_results, stored_count, stored_flag
from osg_control.execution.executor import task_env_config
from osg_control.parallel import LocalExecutor, TaskExecutor
from osg_control.parallel.lazy import grid
from osg_control.perception.spec import PerceptionSpec
from osg_control.seeding import skill_seed


def episode_rng(seed: int, name: str, cell: int, index: int) -> np.random.Generator:
    """The generator of episode ``index`` of the cell (``name``, ``cell``)."""
    return np.random.default_rng(np.random.SeedSequence([skill_seed(seed, name), cell, index]))


def cell_means(
    results: Iterable[Any], cells: int, per_cell: int, desc: str, progress: bool
) -> np.ndarray:
    """The mean of each cell's ``per_cell`` consecutive outcomes (booleans, or tuples of
    them), summed as they arrive (one progress bar over them, on stderr)."""
    sums: np.ndarray | None = None
    bar = tqdm(results, total=cells * per_cell, desc=desc, unit="ep", disable=not progress)
    for j, outcome in enumerate(bar):
        value = np.asarray(outcome, dtype=float)
        if sums is None:
            sums = np.zeros((cells, *value.shape))
        sums[j // per_cell] += value
    assert sums is not None  # every cell has at least one episode
    return sums / per_cell


@cache
def cached_executor(
    domain: str, models: str | None, max_replans: int, filter_gain: float | None
) -> Any:
    """The domain's executor over a defaults directory, one per worker process."""
    from osg_control.execution.executor import load_executor

    return load_executor(
        get_domain(domain), models, max_replans=max_replans, filter_gain=filter_gain
    )


@cache
def _plain_env(domain: str, perception: PerceptionSpec) -> SkillEnv:
    return get_domain(domain).make_env(config=task_env_config(perception))


@dataclass(frozen=True)
class StartEpisode:
    """One episode from a random start in one of a domain's start regions; ``name`` is the
    cell's skill or task (its seeds derive from it)."""

    domain: str
    name: str
    models: str | None
    region: int
    perception: PerceptionSpec
    seed: int
    cell: int
    index: int
    randomize: bool = False


def _reset_in_region(env: SkillEnv, task: StartEpisode, facts: Sequence[str]) -> np.ndarray:
    """A start in the episode's region; with ``randomize`` the objects placed at random in
    their regions (drawn after the reset seed: the fixed-placement starts are unchanged)."""
    rng = episode_rng(task.seed, task.name, task.cell, task.index)
    domain = get_domain(task.domain)
    region = domain.start_regions[task.region]
    reset_seed = int(rng.integers(2**31))
    options: dict[str, Any] = {
        "position": region.position,
        "radius": region.radius,
        "angle": region.angle,
        "gripper": "open",
        "facts": tuple(facts),
    }
    if task.randomize:
        world = env.placement_world(sample_placements(domain, rng), None)
        if world:
            options["world"] = world
    obs, _ = env.reset(seed=reset_seed, options=options)
    return obs


def run_reach_episode(task: StartEpisode) -> tuple[bool, bool, bool]:
    """Table III: classify a random start, run the chosen movement skill.

    Returns:
        (success, whether the start lay outside the chosen skill's initiation region,
        success of the nearest-start-node baseline from the same start).
    """
    domain = get_domain(task.domain)
    executor = cached_executor(task.domain, task.models, 0, None)
    env = _plain_env(task.domain, task.perception)
    region = domain.start_regions[task.region]
    outcomes = []
    outside = False
    for chooser in ("classifier", "nearest"):
        # In the region's facts (e.g. a world where every movement skill's path is clear).
        obs = _reset_in_region(env, task, region.facts)
        if chooser == "classifier":
            skill = domain.skill(str(executor.classifier.predict(obs)))  # the percept
            start = np.asarray(domain.nodes[skill.start].position)
            outside = bool(np.linalg.norm(env.tcp_pose()[0] - start) > skill.start_radius)
        else:
            skill = domain.skill(nearest_start_skill(domain, env.tcp_pose()[0]))
        executor.run_skill(env, skill, obs)
        outcomes.append(env.skill_success(skill))  # scored on the simulator's truth
    return outcomes[0], outside, outcomes[1]


def nearest_start_skill(domain: Domain, position: np.ndarray) -> str:
    """The movement skill whose start node is nearest to a TCP position (the baseline)."""
    return nearest_start(domain.movement_skills, domain.nodes, position).name


def reach_table(
    domain: Domain,
    models: str | None = None,
    episodes: int = 200,
    seed: int = 0,
    workers: int = 2,
    executor: TaskExecutor | None = None,
    progress: bool = False,
    perception: PerceptionSpec | None = None,
) -> dict[str, Any]:
    """Table III: entry-skill success from random starts around the domain's start regions.

    ``perception``: what the robot perceives, whole as the command line gave it (default:
    the paper's protocol without noise); ``executor``: where the episodes run (default: a
    local pool of ``workers``); ``progress``: show a progress bar on stderr.
    """
    regions = domain.start_regions
    seen = perception or PerceptionSpec()
    tasks = grid(
        range(len(regions)),
        episodes,
        lambda r, i: StartEpisode(domain.ref, "reach", models, r, seen, seed, r, i),
    )
    executor = executor or LocalExecutor(workers)
    outcomes = executor.map(run_reach_episode, tasks)
    results = cell_means(outcomes, len(regions), episodes, "reach", progress)
    rows = [
        {
            "start": region.name,
            "success": r[0],
            "outside_initiation": r[1],
            "nearest_node_success": r[2],
        }
        for region, r in zip(regions, results.tolist(), strict=True)
    ]
    return {
        "episodes": episodes,
        "seed": seed,
        "noise": seen.tcp_noise,
        "perception": seen.to_dict(),
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
    """One full-pipeline episode of a task from a start region, scored for each replanning
    budget in ``budgets`` (the largest is run)."""

    start: StartEpisode
    task: str
    budgets: tuple[int, ...]
    filter_gain: float | None = None


def run_task_episode(episode: TaskEpisode) -> list[list[float]]:
    """Tables IV/V: run the executor on a task from a random start with the largest
    replanning budget; per budget (in ``episode.budgets`` order), whether the goal held in
    the simulator where an executor with that budget stops, and how many skills it had run.

    An executor with budget k runs exactly the first k + 1 attempts of one with more (the
    same seeds, the same steps), so one run scores every budget (``Executor.execute``'s
    ``after_attempt``)."""
    start = episode.start
    domain = get_domain(start.domain)
    task = domain.task(episode.task)
    env = _plain_env(start.domain, start.perception)
    obs = _reset_in_region(env, start, domain.task_world(task))
    executor = cached_executor(
        start.domain, start.models, max(episode.budgets), episode.filter_gain
    )
    goal = set(task.goal)
    ends: dict[int, list[float]] = {}

    def score(attempt: int, result: Any) -> None:
        ends[attempt] = [float(goal <= env.facts()), float(len(result.outcomes))]  # truth

    result = executor.execute(task.goal, env, obs, after_attempt=score)
    final = [float(goal <= env.facts()), float(len(result.outcomes))]
    return [ends.get(budget, final) for budget in episode.budgets]


def check_task_result(episode: TaskEpisode, result: Any) -> None:
    """Whether ``result`` can be ``run_task_episode(episode)``'s (a resumed chunk's): one
    [success, skills run] pair per budget, success 0 or 1, skills run a whole number that
    never falls as the budget grows (an executor with more replans runs at least the skills
    of one with fewer).

    Raises:
        ValueError: naming the budget and the value that cannot be.
    """
    if not isinstance(result, list) or len(result) != len(episode.budgets):
        raise ValueError(f"expected {len(episode.budgets)} budgets' results, got {result!r}")
    counts = {}
    for budget, pair in zip(episode.budgets, result, strict=True):
        if not isinstance(pair, list) or len(pair) != 2:
            raise ValueError(f"replans={budget}: expected [success, skills run], got {pair!r}")
        stored_flag(pair[0], f"replans={budget} success")
        counts[budget] = stored_count(pair[1], f"replans={budget} skills run")
    ordered = [counts[b] for b in sorted(counts)]
    if ordered != sorted(ordered):
        raise ValueError(f"skills run fall as the budget grows: {counts}")


def task_table(
    domain: Domain,
    models: str | None = None,
    episodes: int = 100,
    seed: int = 0,
    workers: int = 2,
    tasks: Sequence[str] | None = None,
    replans: Sequence[int] = (0, 2),
    filter_gain: float | None = None,
    executor: TaskExecutor | None = None,
    resume_dir: Path | None = None,
    progress: bool = False,
    perception: PerceptionSpec | None = None,
    randomize: bool = False,
) -> dict[str, Any]:
    """Tables IV and V: task success per start region, without and with replanning,
    scored on the simulator's truth (the goal facts hold at the end), each task in the
    scene of its objects (``Domain.for_task``); ``randomize``: the objects placed at
    random in their regions (seeded per episode). Each episode is run
    once, with the largest budget in ``replans``, and scored for every budget
    (``run_task_episode``).

    ``perception``: what the robot perceives, whole as the command line gave it (default:
    the paper's protocol at its 2 cm); ``tasks``: task names (default: all the domain's);
    ``filter_gain``: the executor's ``TcpFilter`` gain (None: raw observations);
    ``executor``: where the episodes run (default: a local pool of ``workers``);
    ``resume_dir``: keep finished episodes there and resume from them (``resume``);
    ``progress``: show a progress bar on stderr.
    """
    regions = domain.start_regions
    tasks = [domain.task(t).name for t in (tasks or [t.name for t in domain.tasks])]
    cells = [(t, r) for t in tasks for r in range(len(regions))]
    seen = perception or PerceptionSpec(tcp_noise=0.02)
    budgets = tuple(int(k) for k in replans)

    scenes = {t: domain.for_task(domain.task(t)).ref for t in tasks}  # e.g. two cubes

    def job(cell: tuple[str, int], i: int) -> TaskEpisode:
        t, r = cell
        return TaskEpisode(
            StartEpisode(scenes[t], t, models, r, seen, seed, r, i, randomize),
            t,
            budgets,
            filter_gain,
        )

    executor = executor or LocalExecutor(workers)
    results = resumable_results(
        executor, run_task_episode, grid(cells, episodes, job), resume_dir, check_task_result
    )
    means = cell_means(results, len(cells), episodes, "tasks", progress)  # (cells, budgets, 2)
    shape = (len(tasks), len(regions), len(budgets))
    rates = means[:, :, 0].reshape(shape).transpose(2, 0, 1)
    skills_run = means[:, :, 1].reshape(shape).transpose(2, 0, 1)
    return {
        "episodes": episodes,
        "seed": seed,
        "noise": seen.tcp_noise,
        "perception": seen.to_dict(),
        "randomized_objects": randomize,
        "filter_gain": filter_gain,
        "regions": [region.name for region in regions],
        "tasks": list(tasks),
        "replans": list(replans),
        "rates": rates.tolist(),
        "averages": rates.mean(axis=2).tolist(),
        "skills_executed": skills_run.mean(axis=2).tolist(),
    }


def format_task_table(table: dict[str, Any]) -> str:
    """Tables IV and V as text, one block per replanning budget."""
    lines = []
    for k, budget in enumerate(table["replans"]):
        lines.append(
            f"Tables IV/V: task success, {table['perception']['name']} perception, "
            f"sigma = {table['noise']:g} m, max replans = {budget} "
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
        executed = "".join(f" {v:19.2f}" for v in table["skills_executed"][k])
        lines.append(f"   {'skills executed (mean)':34s}{executed}")
        lines.append("")
    return "\n".join(lines)
