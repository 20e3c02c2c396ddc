"""Count the instructions of a kitchen env step against its physics, under Valgrind.

Wall-time ratios of the env step's overhead move by +-0.1 from run to run on a shared VM
(``tools/bench_control.py``); instruction counts do not. This tool runs the same short
script three times under ``valgrind --tool=callgrind`` (set-up only; set-up then
``--steps`` env steps; set-up then ``--steps`` bare ``mj_step(model, data, n_substeps)``
calls) and reports, per control step:

- ``step_instructions``: instructions of one ``KitchenEnv.step``;
- ``physics_instructions``: instructions of its physics alone;
- ``overhead``: ``(step - physics) / physics``, in instructions.

Comparing it with ``bench_control.py``'s wall-time overhead on the same machine gives how
much slower, per instruction, the per-step Python runs than MuJoCo's physics (cache and
branch misses, not work). ``--baseline DIR`` counts a second checkout (e.g. a ``git
worktree`` of an older commit) in the same way, for an A/B that machine noise cannot blur.

The set-up's own count varies by a few 10 M instructions from run to run (imports,
allocation), about +-0.02 of the overhead at 400 steps: more steps resolve finer
differences. Needs Valgrind (``apt-get install valgrind``); about 2 min per count.
Usage::

    python tools/bench_step_instructions.py [--steps 400] [--baseline DIR] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
MODES = ("setup", "step", "physics")
WARMUP_STEPS = 20

_SCRIPT = """
import sys, warnings
import mujoco
import numpy as np
warnings.simplefilter("ignore")
from osg_control.kitchen.env import KitchenEnv
mode, steps, warmup = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
env = KitchenEnv()
env.reset(seed=0)
actions = np.random.default_rng(0).uniform(-0.5, 0.5, (steps + warmup, 7)) * env.action_bounds
actions[:, 6] = 0.0
for action in actions[:warmup]:
    env.step(action)
if mode == "step":
    for action in actions[warmup:]:
        env.step(action)
elif mode == "physics":
    for _ in range(steps):
        mujoco.mj_step(env.model, env.data, env.n_substeps)
"""


def count(checkout: Path, mode: str, steps: int) -> int:
    """Instructions Valgrind counts for one run of the script in ``mode`` on ``checkout``."""
    # A fixed hash seed: set and dict orders, and so the set-up's count, repeat exactly.
    env = dict(os.environ, PYTHONPATH=str(checkout), PYTHONHASHSEED="0")
    command = [
        "valgrind",
        "--tool=callgrind",
        "--callgrind-out-file=/dev/null",
        sys.executable,  # the interpreter itself, not a launcher script Valgrind would stop at
        "-c",
        _SCRIPT,
        mode,
        str(steps),
        str(WARMUP_STEPS),
    ]
    result = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    found = re.search(r"Collected\s*:\s*(\d+)", result.stderr)
    if result.returncode != 0 or found is None:
        raise RuntimeError(f"valgrind run ({mode}, {checkout}) failed:\n{result.stderr[-2000:]}")
    return int(found.group(1))


def measure(checkout: Path, steps: int) -> dict[str, float]:
    """Per-step instructions of the env step and of its physics, and their overhead."""
    totals = {mode: count(checkout, mode, steps) for mode in MODES}
    step = (totals["step"] - totals["setup"]) / steps
    physics = (totals["physics"] - totals["setup"]) / steps
    return {
        "step_instructions": step,
        "physics_instructions": physics,
        "overhead": (step - physics) / physics,
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Count and print (``--json``: one JSON object)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=400, help="counted steps (default 400)")
    parser.add_argument("--baseline", type=Path, help="a second checkout to count the same way")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    if args.steps < 1:
        parser.error("--steps must be at least 1")
    if shutil.which("valgrind") is None:
        parser.error("valgrind is not installed (apt-get install valgrind)")
    checkouts = {"this": REPO}
    if args.baseline is not None:
        if not (args.baseline / "osg_control").is_dir():
            parser.error(f"--baseline {args.baseline}: no osg_control package there")
        checkouts["baseline"] = args.baseline.resolve()
    report = {name: measure(path, args.steps) for name, path in checkouts.items()}
    if args.json:
        print(json.dumps(report, indent=2))
        return report
    for name, figures in report.items():
        print(
            f"{name:8s} env step {figures['step_instructions'] / 1e6:7.3f} M instructions, "
            f"physics {figures['physics_instructions'] / 1e6:7.3f} M, "
            f"overhead {figures['overhead']:.4f}"
        )
    return report


if __name__ == "__main__":
    main()
