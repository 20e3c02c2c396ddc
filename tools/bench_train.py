"""Benchmark TD3+BC training: updates/s of one skill alone and of all skills batched.

Usage::

    python tools/bench_train.py [--data DIR] [--synthetic] [--steps 200] [--repeats 3]
                                [--threads N] [--device cpu|cuda] [--json]

Skill data sets are read from ``DIR/<skill>.h5`` (default ``<cache>/data``); if none is
there, or with ``--synthetic``, synthetic ones of realistic size (``--synthetic-steps`` per
skill, straight noisy moves between each skill's start and end nodes) are written to a
temporary directory instead. Each configuration runs ``--warmup`` updates, then
``--repeats`` timed runs of ``--steps`` updates; the best run is reported (the machine may
be shared). A skill-update is one skill's TD3+BC update (batch 256 by default), so
skill-updates/s = updates/s x skills. ``GFLOP/s`` counts the matmul work only.
Skill-updates per CPU-second (process time, all threads) is the figure that other jobs on
the machine disturb least; with one thread it is what one idle core would reach.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

from osg_control.data.datasets import Episode, write_episodes
from osg_control.domain.spaces import ACTION_DIM, OBS_DIM
from osg_control.kitchen.domain import kitchen_domain
from osg_control.kitchen.skills import NODES, SKILLS, SkillSpec
from osg_control.kitchen.world import WORLD_FIELDS
from osg_control.learning.replay import BatchedReplay
from osg_control.learning.td3bc import TD3BC, TD3BCConfig
from osg_control.paths import cache_dir
from osg_control.pipeline.train import load_skill_input
from osg_control.seeding import skill_seed

ACTION_SCALE = np.asarray(kitchen_domain().action_bounds, dtype=np.float32)
"""The kitchen's action bounds (its data's training scale)."""

D3RLPY_UPDATES_PER_S = 127.0
"""d3rlpy's TD3PlusBC on the 2-core development machine (batch 256, 256-unit networks)."""
EPISODE_STEPS = 80
"""Length of a synthetic episode."""


def synthetic_episode(skill: SkillSpec, rng: np.random.Generator) -> Episode:
    """A noisy straight move from the skill's start node to its end node, ending in success.

    Args:
        skill: whose nodes to move between.
        rng: the noise source.

    Returns:
        An ``EPISODE_STEPS``-step episode with in-bound actions and the reward on the last step.
    """
    start = np.array(NODES[skill.start].position) + rng.normal(0.0, 0.02, 3)
    end = np.array(NODES[skill.end].position)
    moves = (end - start) / EPISODE_STEPS + rng.normal(0.0, 0.003, (EPISODE_STEPS, 3))
    actions = rng.normal(0.0, 0.3, (EPISODE_STEPS, ACTION_DIM)) * ACTION_SCALE
    actions[:, :3] = moves
    actions = np.clip(actions, -ACTION_SCALE, ACTION_SCALE).astype(np.float32)
    positions = start + np.concatenate([np.zeros((1, 3)), np.cumsum(actions[:, :3], 0)])
    obs = np.zeros((EPISODE_STEPS + 1, OBS_DIM), dtype=np.float32)
    obs[:, :3] = positions
    obs[:, 3:7] = (0.0, 1.0, 0.0, 0.0)
    obs[:, 7] = 1.0 if NODES[skill.end].gripper == "closed" else 0.0
    obs[:, 8:] = rng.uniform(0.0, 0.08, (EPISODE_STEPS + 1, 2))
    last = np.arange(EPISODE_STEPS) == EPISODE_STEPS - 1
    return Episode(
        observations=obs[:-1],
        next_observations=obs[1:],
        actions=actions,
        rewards=last.astype(np.float32),
        terminations=last,
        truncations=np.zeros(EPISODE_STEPS, dtype=bool),
        world_states=np.zeros((EPISODE_STEPS, len(WORLD_FIELDS)), dtype=np.float32),
    )


def write_synthetic_data(directory: Path, steps_per_skill: int, seed: int) -> None:
    """Write ``<skill>.h5`` for every skill, about ``steps_per_skill`` steps each."""
    rng = np.random.default_rng(seed)
    for skill in SKILLS:
        episodes = [
            synthetic_episode(skill, rng) for _ in range(max(1, steps_per_skill // EPISODE_STEPS))
        ]
        write_episodes(
            directory / f"{skill.name}.h5",
            episodes,
            {
                "domain": "kitchen",
                "skill": skill.to_json(),
                "seed": seed,
                "world_fields": ",".join(WORLD_FIELDS),
            },
        )


def matmul_gflop_per_update(config: TD3BCConfig) -> float:
    """Matmul work of one skill-update [GFLOP] (forward = 1, backward = 2 passes).

    Target actor and twin target critics forward; twin critics forward and backward; every
    ``policy_freq`` updates, actor and Q1 forward and backward.
    """
    hidden = list(config.hidden_sizes)

    def multiply_adds(sizes: list[int]) -> int:
        return sum(a * b for a, b in zip(sizes[:-1], sizes[1:], strict=True))

    actor = multiply_adds([OBS_DIM, *hidden, ACTION_DIM])
    critic = multiply_adds([OBS_DIM + ACTION_DIM, *hidden, 1])
    per_sample = actor + 2 * critic + 3 * 2 * critic + 3 * (actor + critic) / config.policy_freq
    return 2 * per_sample * config.batch_size / 1e9


def bench(names: list[str], data_dir: Path, args: argparse.Namespace) -> dict[str, Any]:
    """Time ``args.steps`` updates of the named skills batched (best of ``args.repeats``)."""
    config = TD3BCConfig()
    inputs = [load_skill_input(data_dir, name, config, ACTION_SCALE) for name in names]
    seeds = [skill_seed(0, name) for name in names]
    replay = BatchedReplay([i.data for i in inputs], config.batch_size, seeds, args.device)
    trainer = TD3BC(config, seeds, device=args.device)
    wall, cpu = float("inf"), float("inf")
    for run in range(args.repeats + 1):
        steps = args.warmup if run == 0 else args.steps
        start_wall, start_cpu = time.perf_counter(), time.process_time()
        for _ in range(steps):
            trainer.train_step(replay.sample())
        if args.device == "cuda":
            torch.cuda.synchronize()
        if run:
            wall = min(wall, time.perf_counter() - start_wall)
            cpu = min(cpu, time.process_time() - start_cpu)
    skill_updates = args.steps * len(names)
    return {
        "skills": len(names),
        "updates_per_s": args.steps / wall,
        "skill_updates_per_s": skill_updates / wall,
        "x_d3rlpy": skill_updates / wall / D3RLPY_UPDATES_PER_S,
        "gflop_per_s": skill_updates / wall * matmul_gflop_per_update(config),
        "skill_updates_per_cpu_s": skill_updates / cpu,
    }


def main() -> None:
    """Parse arguments, find or make the data, run both configurations, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=cache_dir() / "data")
    parser.add_argument("--synthetic", action="store_true", help="ignore --data, make data")
    parser.add_argument("--synthetic-steps", type=int, default=20_000, help="steps per skill")
    parser.add_argument("--steps", type=int, default=200, help="timed updates per run")
    parser.add_argument("--warmup", type=int, default=20, help="untimed updates first")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs; the best counts")
    parser.add_argument(
        "--threads", type=int, default=None, help="torch threads (default: torch's)"
    )
    parser.add_argument("--device", choices=("cpu", "cuda"), default="cpu")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args()
    if args.threads:
        torch.set_num_threads(args.threads)

    with tempfile.TemporaryDirectory(prefix="osg-bench-") as tmp:
        names = [s.name for s in SKILLS if (args.data / f"{s.name}.h5").is_file()]
        data_dir, source = args.data, str(args.data)
        if args.synthetic or not names:
            data_dir, source = Path(tmp), f"synthetic, {args.synthetic_steps} steps per skill"
            write_synthetic_data(data_dir, args.synthetic_steps, seed=0)
            names = [s.name for s in SKILLS]
        results = [bench(names[:1], data_dir, args), bench(names, data_dir, args)]

    config = TD3BCConfig()
    report = {
        "data": source,
        "device": args.device,
        "threads": torch.get_num_threads(),
        "batch_size": config.batch_size,
        "hidden_sizes": list(config.hidden_sizes),
        "steps": args.steps,
        "repeats": args.repeats,
        "d3rlpy_updates_per_s": D3RLPY_UPDATES_PER_S,
        "results": results,
    }
    if args.json:
        print(json.dumps(report, indent=2))
        return
    print(
        f"TD3+BC, batch {config.batch_size}, hidden {config.hidden_sizes}, {args.device}, "
        f"{report['threads']} thread(s), data: {source}"
    )
    print(
        f"{'skills':>6} {'updates/s':>10} {'skill-updates/s':>16} {'x d3rlpy':>9} "
        f"{'GFLOP/s':>8} {'skill-updates/CPU-s':>20}"
    )
    for r in results:
        print(
            f"{r['skills']:>6} {r['updates_per_s']:>10.1f} {r['skill_updates_per_s']:>16.1f} "
            f"{r['x_d3rlpy']:>9.2f} {r['gflop_per_s']:>8.1f} {r['skill_updates_per_cpu_s']:>20.1f}"
        )


if __name__ == "__main__":
    main()
