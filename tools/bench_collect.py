"""Benchmark scripted data collection: episodes/s per backend, Ray's overhead against the
local pool, and a projection to the paper's scale on N nodes.

Usage: python tools/bench_collect.py [--backend local ray] [--skill NAME] [--episodes N]
       [--workers W] [--nodes 1 4 16] [--json]
Every run collects the same episodes (same seed) into a temporary directory; Ray runs on a
local instance of ``--workers`` CPUs, started before its clock starts. The projection takes
the measured seconds per episode per CPU and assumes ``--workers`` CPUs per node:
14 skills x 10K episodes (collection) and 8 regions x 1,000 reach episodes (Table III,
costed from a short reach run of ``--reach-episodes`` per region on the local pool).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path
from typing import Any

from osg_control.data.collect import collect_skill
from osg_control.domain.registry import get_domain
from osg_control.evaluation.evaluate import reach_table
from osg_control.parallel import open_executor

PAPER_COLLECTION = 14 * 10_000
PAPER_REACH = 8 * 1_000


def measure(backend: str, skill: str, episodes: int, workers: int, chunk: int) -> dict[str, Any]:
    """Collect ``episodes`` episodes on one backend; return its wall time and rates."""
    with open_executor(backend, workers) as executor, tempfile.TemporaryDirectory() as tmp:
        started = time.perf_counter()
        data = collect_skill(
            get_domain("kitchen"),
            skill,
            episodes,
            0,
            Path(tmp),
            executor,
            False,
            chunk_episodes=chunk,
        )
        seconds = time.perf_counter() - started
    return {
        "backend": backend,
        "workers": workers,
        "seconds": seconds,
        "episodes_per_s": episodes / seconds,
        "steps_per_s": data.num_steps / seconds,
        "cpu_seconds_per_episode": seconds * workers / episodes,
    }


def reach_cpu_seconds(episodes: int, workers: int) -> float:
    """CPU-seconds per Table III episode, from ``episodes`` per region on the local pool."""
    started = time.perf_counter()
    reach_table(get_domain("kitchen"), None, episodes, 0, workers)
    return (time.perf_counter() - started) * workers / (8 * episodes)


def projection(collect_s: float, reach_s: float, workers: int, nodes: list[int]) -> list[dict]:
    """Hours for the paper's collection and reach test on each node count."""
    return [
        {
            "nodes": n,
            "collection_hours": PAPER_COLLECTION * collect_s / (n * workers) / 3600,
            "reach_hours": PAPER_REACH * reach_s / (n * workers) / 3600,
        }
        for n in nodes
    ]


def main() -> None:
    """Run the benchmark and print (or dump as JSON) the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--backend", nargs="+", default=["local", "ray"])
    parser.add_argument("--skill", default="slide-door-open")
    parser.add_argument("--episodes", type=int, default=120)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--chunk", type=int, default=10, help="episodes per task")
    parser.add_argument("--nodes", type=int, nargs="+", default=[1, 4, 16])
    parser.add_argument("--reach-episodes", type=int, default=2, help="per start region")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    runs = [measure(b, args.skill, args.episodes, args.workers, args.chunk) for b in args.backend]
    by_backend = {run["backend"]: run for run in runs}
    result: dict[str, Any] = {"skill": args.skill, "episodes": args.episodes, "runs": runs}
    if {"local", "ray"} <= set(by_backend):
        result["ray_overhead"] = by_backend["ray"]["seconds"] / by_backend["local"]["seconds"] - 1
    slowest = max(run["cpu_seconds_per_episode"] for run in runs)
    reach_s = reach_cpu_seconds(args.reach_episodes, args.workers)
    result["reach_cpu_seconds_per_episode"] = reach_s
    result["projection"] = projection(slowest, reach_s, args.workers, args.nodes)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    print(f"collection of {args.episodes} episodes of {args.skill}, {args.workers} workers")
    for run in runs:
        print(
            f"  {run['backend']:5s}: {run['seconds']:6.1f} s, {run['episodes_per_s']:6.2f} "
            f"episodes/s, {run['steps_per_s']:7.0f} steps/s, "
            f"{run['cpu_seconds_per_episode']:.3f} CPU-s/episode"
        )
    if "ray_overhead" in result:
        print(f"  Ray overhead vs the local pool: {100 * result['ray_overhead']:+.1f} %")
    print(
        f"projection ({args.workers} CPUs per node; {slowest:.3f} CPU-s per collected "
        f"episode, {reach_s:.3f} per reach episode):"
    )
    for row in result["projection"]:
        print(
            f"  {row['nodes']:3d} node(s): 14 x 10K collection {row['collection_hours']:6.2f} h, "
            f"8 x 1,000 reach {row['reach_hours']:6.2f} h"
        )


if __name__ == "__main__":
    main()
