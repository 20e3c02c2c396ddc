"""Scripted noisy data collection (Algorithm 1): parallel, deterministic, resumable.

Episode ``i`` of a skill draws everything from ``SeedSequence([skill_seed(seed, name), i])``
(``osg_control.seeding``), so the data set is the same whatever the number of workers or the
backend, and adding a skill to a domain changes no other skill's data. Workers return each
chunk's episodes and this process writes the chunk, atomically, under
``<out>/.parts/<skill>/``; an interrupted run keeps every finished chunk and the same
command continues where it stopped. When all chunks exist they are merged
into ``<out>/<skill>.h5`` (atomically) and the parts are removed. Chunk jobs are made on
demand (``parallel.lazy``): memory and the time to the first progress line do not grow
with the number of episodes.
"""

from __future__ import annotations

import re
import shutil
from contextlib import closing
from dataclasses import dataclass
from itertools import tee
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from osg_control import __version__
from osg_control.data.chunks import chunk_attrs, keep_chunk
from osg_control.data.datasets import Dataset, Episode, load_dataset, write_episodes
from osg_control.data.scripted import ScriptedPolicy
from osg_control.domain.base import Domain
from osg_control.domain.contract import SkillEnv
from osg_control.domain.frames import (
    in_skill_frame,
    node_position,
    placement_offsets,
    sample_placements,
    shifted_skill,
    skill_frame,
    skill_offset,
)
from osg_control.domain.registry import get_domain
from osg_control.domain.spec import SkillSpec
from osg_control.environment.config import EnvConfig
from osg_control.parallel import LocalExecutor, TaskExecutor
from osg_control.parallel.lazy import Jobs
from osg_control.seeding import skill_seed

DEFAULT_EPISODES = 300
CHUNK_EPISODES = 25
HOLD_STEPS = 10
"""Steps recorded after an episode's first success, the script holding its last waypoint
(Algorithm 1 acting on it past its budget). Without them the data ends where beta is first
reached, and learned policies that missed the goal by a little under observation noise
carried on past it (see docs/learning.md)."""

_ENVS: dict[tuple[str, str], SkillEnv] = {}


def _env_for(domain: Domain, skill: SkillSpec) -> SkillEnv:
    """One env per skill per process, reused across episodes."""
    key = (domain.ref, skill.to_json())
    if key not in _ENVS:
        _ENVS[key] = domain.make_env(skill=skill, config=EnvConfig())
    return _ENVS[key]


def placed_start_options(
    domain: Domain, env: SkillEnv, skill: SkillSpec, placements: dict[str, np.ndarray]
) -> dict[str, Any]:
    """Reset options of a start with the domain's objects at ``placements``: the objects
    not held placed there (``env.placement_world``), the start node moved with its anchor."""
    options: dict[str, Any] = {"radius": skill.start_radius, "angle": skill.start_angle}
    world = env.placement_world(placements, skill.holding)
    if world:
        options["world"] = world
    if domain.nodes[skill.start].anchor is not None:
        offsets = placement_offsets(domain.objects, placements)
        options["position"] = node_position(domain.nodes, skill.start, offsets).tolist()
    return options


def touches_objects(domain: Domain, skill: SkillSpec) -> bool:
    """Whether a skill's data depend on where the domain's placed objects lie
    (``ObjectFrame.placed``): it acts in such an object's frame, starts at a node anchored
    to one, or starts holding one. The others (the kitchen's door and valve skills; the
    door is an object its handle's node moves with, but Algorithm 1 never places it) are
    recorded with the objects where the scene has them, their data the same as before
    objects could move; so are an ``evaluation_only`` object's)."""
    objects = {f.name for f in domain.objects if f.placed and not f.evaluation_only}
    return bool(
        skill_frame(domain, skill) in objects
        or domain.nodes[skill.start].anchor in objects
        or skill.holding in objects
    )


def run_scripted_episode(
    domain: Domain, skill: SkillSpec, seed: int, index: int, randomize: bool = True
) -> Episode:
    """Run Algorithm 1 for one episode from a random start in the skill's initiation region,
    the domain's objects placed uniformly in their regions when the skill touches them
    (``randomize`` and ``touches_objects``; else where the scene has them). The script aims
    at the objects' true places (its oracle); the data are recorded in the skill's frame
    (``domain.frames``)."""
    rng = np.random.default_rng(np.random.SeedSequence([skill_seed(seed, skill.name), index]))
    env = _env_for(domain, skill)
    reset_seed = int(rng.integers(2**31))
    options: dict[str, Any] = {"radius": skill.start_radius, "angle": skill.start_angle}
    if randomize and touches_objects(domain, skill):
        placements = sample_placements(domain, rng, collecting=True)
        options = placed_start_options(domain, env, skill, placements)
    obs, info = env.reset(seed=reset_seed, options=options)
    offset = skill_offset(domain, skill, env.anchor_offsets)
    script = shifted_skill(skill, offset)
    policy = ScriptedPolicy(script, rng, bounds=env.action_bounds)
    policy.reset()
    rows: dict[str, list[Any]] = {k: [] for k in ("obs", "next", "act", "rew", "term", "world")}
    hold_left: int | None = None  # steps still to record after the first success
    while hold_left != 0 and (hold_left is not None or not policy.done):
        action = policy(obs)
        next_obs, reward, _terminated, truncated, info = env.step(action)
        # Until the first success the env checks beta itself (its reward); after it, the env
        # no longer rewards, so the hold steps are checked here.
        at_goal = reward > 0 or (
            hold_left is not None
            and "failure" not in info
            and env.skill_success(world=info["world"])
        )
        rows["obs"].append(in_skill_frame(obs, offset))
        rows["next"].append(in_skill_frame(next_obs, offset))
        rows["act"].append(info["action_applied"])
        rows["rew"].append(1.0 if at_goal else 0.0)
        rows["term"].append(at_goal)
        rows["world"].append(info["world"])
        obs = next_obs
        if hold_left is not None:
            hold_left -= 1
        elif at_goal:
            hold_left = HOLD_STEPS
        if "failure" in info or truncated:
            break
    truncations = np.zeros(len(rows["act"]), dtype=bool)
    if not rows["term"][-1]:
        truncations[-1] = True
    return Episode(
        observations=np.asarray(rows["obs"], dtype=np.float32),
        next_observations=np.asarray(rows["next"], dtype=np.float32),
        actions=np.asarray(rows["act"], dtype=np.float32),
        rewards=np.asarray(rows["rew"], dtype=np.float32),
        terminations=np.asarray(rows["term"], dtype=bool),
        truncations=truncations,
        world_states=np.asarray(rows["world"], dtype=np.float32),
    )


@dataclass(frozen=True)
class ChunkTask:
    """Episodes ``[start, stop)`` of one skill of a domain, written to ``path``."""

    domain: str
    skill: SkillSpec
    seed: int
    start: int
    stop: int
    path: Path


def _run_chunk(task: ChunkTask) -> list[Episode]:
    """A chunk's episodes; the caller writes them, so workers need no shared file system."""
    domain = get_domain(task.domain)
    return [
        run_scripted_episode(domain, task.skill, task.seed, i) for i in range(task.start, task.stop)
    ]


def _identity(task: ChunkTask) -> dict[str, Any]:
    return chunk_attrs(task.skill.to_json(), task.seed, task.start, task.stop)


def _attrs(domain: Domain, skill: SkillSpec, seed: int) -> dict[str, Any]:
    return {
        "domain": domain.name,
        "skill": skill.to_json(),
        "seed": seed,
        "package_version": __version__,
        "world_fields": ",".join(domain.world_fields),
        "collector": "osg_control.data.collect (Algorithm 1)",
    }


def parts_dir(out: Path, skill: SkillSpec) -> Path:
    """Where the chunks of an unfinished collection live."""
    return out / ".parts" / skill.name


def chunk_tasks(
    domain: Domain, skill: SkillSpec, episodes: int, seed: int, out: Path, chunk_episodes: int
) -> Jobs[ChunkTask]:
    """The collection's chunks, ``chunk_episodes`` each (the last one the rest), on demand."""
    parts = parts_dir(out, skill)

    def chunk(k: int) -> ChunkTask:
        start, stop = k * chunk_episodes, min((k + 1) * chunk_episodes, episodes)
        path = parts / f"seed{seed}_{start:06d}_{stop:06d}.h5"
        return ChunkTask(domain.ref, skill, seed, start, stop, path)

    return Jobs(-(-episodes // chunk_episodes), chunk)


CHUNK_NAME = re.compile(r"seed\d+_(\d+)_\d+\.h5")


def _kept_chunks(tasks: Jobs[ChunkTask], parts: Path, chunk_episodes: int) -> set[int]:
    """The chunks an earlier run finished: files in ``parts`` that are one of ``tasks`` and
    pass ``keep_chunk`` (found from the folder, not by asking about every chunk)."""
    kept = set()
    for path in sorted(parts.glob("*.h5")):
        named = CHUNK_NAME.fullmatch(path.name)
        if named is None:
            continue
        k = int(named.group(1)) // chunk_episodes
        if k < len(tasks) and tasks[k].path == path and keep_chunk(path, _identity(tasks[k])):
            kept.add(k)
    return kept


def collect_skill(
    domain: Domain,
    skill: SkillSpec | str,
    episodes: int,
    seed: int,
    out: Path,
    executor: TaskExecutor | None = None,
    progress: bool = True,
    chunk_episodes: int = CHUNK_EPISODES,
) -> Dataset:
    """Collect ``episodes`` scripted episodes of a skill into ``<out>/<skill>.h5``.

    Finished chunks of an earlier, interrupted run with the same arguments are kept.

    Returns:
        The merged, validated data set.
    """
    skill = domain.skill(skill) if isinstance(skill, str) else skill
    out = Path(out)
    final = out / f"{skill.name}.h5"
    if final.exists():
        existing = load_dataset(final)
        same_skill = existing.attrs["skill"] == skill.to_json()
        if existing.num_episodes == episodes and int(existing.attrs["seed"]) == seed and same_skill:
            return existing
    parts = parts_dir(out, skill)
    tasks = chunk_tasks(domain, skill, episodes, seed, out, chunk_episodes)
    kept = _kept_chunks(tasks, parts, chunk_episodes)
    done_eps = sum(tasks[k].stop - tasks[k].start for k in kept)
    successes = sum(int(load_dataset(tasks[k].path).episode_successes.sum()) for k in kept)
    bar = tqdm(total=episodes, initial=done_eps, desc=skill.name, unit="ep", disable=not progress)
    submitted, written = tee(t for k, t in enumerate(tasks) if k not in kept)
    with closing((executor or LocalExecutor()).map(_run_chunk, submitted)) as chunks:
        for task, chunk in zip(written, chunks, strict=True):
            write_episodes(task.path, chunk, {**_attrs(domain, skill, seed), **_identity(task)})
            done_eps += len(chunk)
            successes += sum(e.success for e in chunk)
            bar.update(len(chunk))
            bar.set_postfix(success=f"{successes / max(done_eps, 1):.2f}")
    bar.close()
    merged = [load_dataset(t.path) for t in tasks]
    all_episodes = [d.episode(i) for d in merged for i in range(d.num_episodes)]
    write_episodes(final, all_episodes, _attrs(domain, skill, seed))
    shutil.rmtree(parts, ignore_errors=True)
    return load_dataset(final)
