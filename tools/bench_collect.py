"""Benchmark scripted data collection: episodes/s and env steps/s with 1 and 2 workers.

Usage: python tools/bench_collect.py [--skill NAME] [--episodes N] [--json]
Both runs collect the same episodes (same seed) into temporary directories; the ratio of
their wall times is the parallel speed-up (target: 2 workers >= 1.8x one worker).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from osg_control.data.collect import LocalExecutor, collect_skill
from osg_control.domain.registry import get_domain


def measure(skill: str, episodes: int, workers: int, chunk: int) -> dict[str, float]:
    """Collect ``episodes`` episodes with ``workers`` processes; return rates."""
    with tempfile.TemporaryDirectory() as tmp:
        started = time.perf_counter()
        data = collect_skill(
            get_domain("kitchen"),
            skill,
            episodes,
            0,
            Path(tmp),
            LocalExecutor(workers),
            False,
            chunk_episodes=chunk,
        )
        seconds = time.perf_counter() - started
    return {
        "workers": workers,
        "seconds": seconds,
        "episodes_per_s": episodes / seconds,
        "steps_per_s": data.num_steps / seconds,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skill", default="slide-door-open")
    parser.add_argument("--episodes", type=int, default=120)
    parser.add_argument("--chunk", type=int, default=10, help="episodes per task")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    runs = [measure(args.skill, args.episodes, w, args.chunk) for w in (1, 2)]
    result = {
        "skill": args.skill,
        "episodes": args.episodes,
        "runs": runs,
        "speedup_2_workers": runs[0]["seconds"] / runs[1]["seconds"],
    }
    if args.json:
        print(json.dumps(result, indent=2))
        return
    print(f"collection of {args.episodes} episodes of {args.skill}")
    for run in runs:
        print(
            f"  {run['workers']} worker(s): {run['seconds']:6.1f} s, "
            f"{run['episodes_per_s']:6.1f} episodes/s, {run['steps_per_s']:7.0f} steps/s"
        )
    print(f"  speed-up with 2 workers: {result['speedup_2_workers']:.2f}x")


if __name__ == "__main__":
    main()
