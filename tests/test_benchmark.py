"""The outside-benchmark protocol (``domain/benchmark.py``) and its scoring
(``evaluation/benchmark.py``), independent of any one domain."""

from __future__ import annotations

import numpy as np
import pytest

from osg_control.cli import main as osg
from osg_control.domain.benchmark import Benchmark, validate_benchmark
from osg_control.errors import DomainError
from osg_control.evaluation.benchmark import format_benchmark, score_interval


def _bench(**changes) -> Benchmark:
    fields = {
        "name": "toy",
        "goal_sets": {"both": ("a", "b"), "one": ("a",)},
        "default_set": "both",
        "task_facts": {"a": "a-done", "b": "b-done"},
        "step_limit": 10,
        "make_env": lambda *args: None,
    }
    fields.update(changes)
    return Benchmark(**fields)


def test_goal_sets_and_goal_facts() -> None:
    bench = _bench()
    assert bench.tasks_of("one") == ("a",)
    assert bench.goal(("b", "a")) == ("b-done", "a-done")
    with pytest.raises(DomainError, match="unknown goal set 'three'.*both, one"):
        bench.tasks_of("three")
    with pytest.raises(DomainError, match=r"unknown task\(s\) \['c'\].*\['a', 'b'\]"):
        bench.goal(("a", "c"))
    with pytest.raises(DomainError, match="unknown task"):
        bench.check_tasks(())


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"default_set": "none"}, "default_set 'none'"),
        ({"goal_sets": {"both": ("a", "z")}}, "goal set 'both'"),
        ({"task_facts": {"a": "a-done", "b": "nope"}}, r"unknown facts \['nope'\]"),
        ({"step_limit": 0}, "step_limit"),
    ],
)
def test_validation_names_the_field(changes, message) -> None:
    with pytest.raises(DomainError, match=message):
        validate_benchmark(_bench(**changes), ("a-done", "b-done"), "domain 'toy'")


def test_score_interval_is_conservative_and_bounded() -> None:
    # Every episode complete: the interval still says how sure 20 episodes make us.
    low, high = score_interval(np.ones(20), 100.0)
    assert high == pytest.approx(100.0) and 80.0 < low < 100.0
    # More episodes, a narrower interval around the same mean.
    mixed = np.array([1.0, 0.75, 0.5, 1.0] * 5)
    low20, high20 = score_interval(mixed, 100.0)
    low80, high80 = score_interval(np.tile(mixed, 4), 100.0)
    assert low20 < low80 < 81.25 < high80 < high20
    # At least as wide as the t-interval the per-episode spread would give.
    half_t = 1.96 * mixed.std(ddof=1) / np.sqrt(len(mixed)) * 100
    assert (high20 - low20) >= 2 * half_t * 0.95


def test_format_names_protocol_score_and_tasks() -> None:
    summary = {
        "benchmark": "toy",
        "goal_set": "both",
        "tasks": ["a", "b"],
        "episodes": 4,
        "seed": 0,
        "score": 87.5,
        "interval": [60.0, 97.0],
        "full_rate": 0.75,
        "task_rates": {"a": 1.0, "b": 0.75},
        "steps": {"mean": 120.0, "max": 280},
        "step_limit": 280,
        "perturbed": True,
        "noise": 0.02,
        "filter_gain": 0.3,
        "failures": {"b: timeout": 1},
    }
    text = format_benchmark(summary)
    assert "score 87.5" in text and "60.0-97.0" in text
    assert "step limit 280" in text and "perturbed starts" in text and "+ filter" in text
    assert "failure x1: b: timeout" in text


def test_a_domain_without_a_benchmark_is_a_clear_error(capsys) -> None:
    code = osg(["--domain", "kitchen", "evaluate", "benchmark", "--episodes", "1"])
    assert code == 1
    assert "has no outside benchmark" in capsys.readouterr().err
