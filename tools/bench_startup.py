"""Benchmark the CLI's start-up: wall time and peak memory of ``osg`` calls that do no work.

Each command runs ``--repeats`` times in a fresh interpreter (``python -m osg_control.cli``);
the median wall time and the largest peak resident memory are printed. Also reports whether
torch was imported, which only the verbs that train or load a model may do.

    python tools/bench_startup.py [--repeats 5] [--json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time

COMMANDS = (
    ("--help",),
    ("plan", "--help"),
    ("plan", "--goal", "door-open cube-in-cabinet"),
)
"""The measured calls: the verb list, the planner's help, and a kitchen plan end to end."""
_PROBE = """
import resource, sys
sys.argv = ["osg", *sys.argv[1:]]
try:
    from osg_control.cli import main
    code = main()
finally:
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print("torch" in sys.modules, peak, file=sys.stderr)
sys.exit(code)
"""
"""Runs ``osg`` in the child and reports, last on stderr, torch's import and peak memory [KB]."""


def measure(command: tuple[str, ...], repeats: int) -> dict[str, object]:
    """Median wall seconds, peak memory [MB] and torch import of ``osg COMMAND``."""
    times, peaks, torch = [], [], False
    for _ in range(repeats):
        start = time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-c", _PROBE, *command], capture_output=True, text=True, check=False
        )
        times.append(time.perf_counter() - start)
        flag, peak_kb = done.stderr.strip().splitlines()[-1].split()
        peaks.append(int(peak_kb) / 1024)
        torch = torch or flag == "True"
    return {
        "command": "osg " + " ".join(command),
        "median_s": statistics.median(times),
        "peak_mb": max(peaks),
        "imports_torch": torch,
    }


def main() -> int:
    """Measure every command and print a table (or JSON)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="runs per command (median)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args()
    rows = [measure(c, args.repeats) for c in COMMANDS]
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        for row in rows:
            print(
                f"{row['command']:<48} {row['median_s']:6.2f} s  {row['peak_mb']:6.0f} MB  "
                f"torch: {'yes' if row['imports_torch'] else 'no'}"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
