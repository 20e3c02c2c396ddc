"""The benchmark scripts under ``tools/`` run: each on its smallest work, as a user runs it
(a subprocess from the repository root), its JSON report read back."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _report(*command: str) -> dict:
    done = subprocess.run(
        [sys.executable, *command, "--json"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout)


@pytest.mark.slow
def test_bench_train_on_synthetic_data() -> None:
    """The synthetic data sets are valid ones (the loader's checks) and both configurations
    train on them."""
    report = _report(
        "tools/bench_train.py", "--synthetic", "--synthetic-steps", "80",
        "--steps", "2", "--warmup", "1", "--repeats", "1", "--threads", "1",
    )  # fmt: skip
    one, batched = report["results"]
    assert one["skills"] == 1 and batched["skills"] > 1
    assert batched["skill_updates_per_s"] > 0 and one["updates_per_s"] > 0


@pytest.mark.slow
def test_bench_control_reports_its_targets() -> None:
    report = _report("tools/bench_control.py", "--solves", "5", "--warmup", "4", "--env-steps", "5")
    assert set(report["ik"]) == {"mink-daqp", "mink-osqp", "pinocchio-daqp", "pinocchio-osqp"}
    env = report["env"]
    assert env["physics_median_us"] > 0 and env["n_substeps"] == 25
    assert set(report["targets"]) >= {"overhead_le_25pct"}


def test_bench_lifted_plans_three_cubes_alike_in_every_planner() -> None:
    report = _report("tools/bench_lifted.py", "--count", "3", "--repeats", "1")
    assert report["objects"] == ["cube-1", "cube-2", "cube-3"]
    costs = {row["planner"]: row["cost"] for row in report["planners"]}
    assert len(set(costs.values())) == 1 and all(r["steps"] == 22 for r in report["planners"])
    assert report["fast_downward_cost"] in (None, costs["auto"])  # None: not installed
