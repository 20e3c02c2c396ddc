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


def test_skill_failures_reads_the_truth_of_table_i_episodes() -> None:
    """Without noise the tracker's frame is right to millimetres (the cube settles in the
    hand); with the filter warmed the summary says so and every failure ran within the
    skill's budget."""
    exact = _report("tools/skill_failures.py", "--skill", "pick-up-cube", "--episodes", "3",
                    "--noise", "0", "--workers", "1")  # fmt: skip
    assert exact["noise"] == 0.0 and exact["filter_gain"] is None
    assert exact["success"] == 0.0 or exact["frame_error_succeeded"] < 0.005
    warm = _report("tools/skill_failures.py", "--skill", "push-valve-open", "--episodes", "3",
                   "--filter", "--warm-readings", "4", "--workers", "1")  # fmt: skip
    assert warm["warm_readings"] == 4 and warm["filter_gain"] == 0.2
    assert warm["frame_error_succeeded"] == 0.0  # the valve's frame, read exactly (paper)
    assert all(f["steps"] <= 80 and not f["success"] for f in warm["failures"])
    assert 0.0 <= warm["success"] <= 1.0 and len(warm["failures"]) <= 3


def test_skill_failures_refuses_warm_readings_without_the_filter() -> None:
    done = subprocess.run(
        [sys.executable, "tools/skill_failures.py", "--skill", "grab-cube", "--warm-readings", "3"],
        cwd=ROOT, capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip
    assert done.returncode == 2 and "--filter" in done.stderr


def test_task_failures_runs_the_paper_protocol() -> None:
    """``--noise`` and ``--filter`` reach the episodes: the summary records them."""
    report = _report("tools/task_failures.py", "--task", "turn-valve", "--episodes", "1",
                     "--perception", "paper", "--noise", "0.02", "--filter")  # fmt: skip
    assert report["perception"]["tcp_noise"] == 0.02 and report["filter_gain"] == 0.2
    assert report["episodes"] == 8 and len(report["failures"]) == round(8 * (1 - report["success"]))
