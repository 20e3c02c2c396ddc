"""The FrankaKitchen-v1 benchmark end to end on the shipped defaults: plan, execute and
score by the env's own completions."""

from __future__ import annotations

import pytest

pytest.importorskip("gymnasium_robotics")

from osg_control.cli import main as osg  # noqa: E402
from osg_control.domain.registry import get_domain  # noqa: E402
from osg_control.errors import DomainError  # noqa: E402
from osg_control.evaluation.benchmark import run_benchmark  # noqa: E402

KITCHEN_COMPLETE = ("microwave", "kettle", "light switch", "slide cabinet")


def test_kitchen_complete_from_the_envs_reset_completes_all_four() -> None:
    """One episode on a fixed seed, the standard protocol (the env's reset, its 280-step
    limit, its own completion record): all four tasks, within the limit."""
    summary = run_benchmark(get_domain("franka-kitchen"), episodes=1, seed=0, workers=1)
    assert summary["tasks"] == list(KITCHEN_COMPLETE)
    assert summary["task_rates"] == {task: 1.0 for task in KITCHEN_COMPLETE}
    assert summary["score"] == 100.0 and summary["full_rate"] == 1.0
    assert summary["steps"]["max"] <= 280 and summary["step_limit"] == 280


def test_unknown_goal_set_and_task_are_named(capsys) -> None:
    domain = get_domain("franka-kitchen")
    with pytest.raises(DomainError, match="unknown goal set 'kitchen-partial'"):
        run_benchmark(domain, goal_set="kitchen-partial", episodes=1)
    code = osg(["--domain", "franka-kitchen", "evaluate", "benchmark", "--tasks", "toaster"])
    err = capsys.readouterr().err
    assert code == 1 and "unknown task(s) ['toaster']" in err and "'microwave'" in err
