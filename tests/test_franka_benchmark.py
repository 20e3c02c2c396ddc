"""The FrankaKitchen-v1 benchmark end to end on the shipped defaults: plan, execute and
score by the env's own completions."""

from __future__ import annotations

import pytest

pytest.importorskip("gymnasium_robotics")

from osg_control.cli import main as osg  # noqa: E402
from osg_control.domain.registry import get_domain  # noqa: E402
from osg_control.errors import DomainError  # noqa: E402
from osg_control.evaluation.benchmark import (  # noqa: E402
    BenchmarkEpisode,
    _benchmark_env,
    benchmark_of,
    benchmark_perception,
    run_benchmark,
    run_benchmark_episode,
)

KITCHEN_COMPLETE = ("microwave", "kettle", "light switch", "slide cabinet")


@pytest.mark.slow
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
    assert code == 2 and "unknown task(s) ['toaster']" in err and "'microwave'" in err  # usage


@pytest.mark.slow
@pytest.mark.parametrize(
    ("index", "noise", "filter_gain"),
    [(0, 0.0, None), (17, 0.0, None), (68, 0.0, None), (40, 0.02, 0.5)],
)
def test_no_env_step_after_the_episode_is_over_and_never_past_280(
    index, noise, filter_gain, monkeypatch
) -> None:
    """The env's protocol: no step after one came back terminated or truncated, at most
    280 steps. Seed 0's episode 0 completes all four tasks (the env terminates mid-skill);
    17 and 68 reach the limit at the end of a skill, where a joint reset or the next skill
    used to take one or two steps more (281-282); with 2 cm TCP noise and the filter,
    episode 40 reaches it in a skill, after which opening the gripper for the replan took
    five steps more (285)."""
    domain = get_domain("franka-kitchen")
    bench = benchmark_of(domain)
    tasks = bench.tasks_of(bench.default_set)
    perception = benchmark_perception(domain, None, noise) if noise else None
    adapter = _benchmark_env("franka-kitchen", tasks, bench.step_limit, perception, 0, "")
    ends: list[bool] = []
    library_step = adapter.env.step

    def recorded_step(action):
        outcome = library_step(action)
        ends.append(bool(outcome[2] or outcome[3]))
        return outcome

    monkeypatch.setattr(adapter.env, "step", recorded_step)
    episode = BenchmarkEpisode(
        "franka-kitchen", None, bench.default_set, tasks, 0, index, perception, filter_gain
    )
    result = run_benchmark_episode(episode)
    assert len(ends) == result["steps"] <= 280
    assert True not in ends[:-1], f"a step after the episode ended ({result})"
    assert ends[-1] or result["failure"] is None


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--env-kwargs", "[1]"], "must be a JSON object"),
        (["--env-kwargs", "{nope"], "not JSON"),
        (["--perception", "robot"], "does not support perception 'robot'"),
        (["--perception", "sim", "--noise", "0.02"], "no --noise"),
        (["--perception", "x-ray"], "unknown perception 'x-ray'"),
        (["--env-kwargs", '{"bogus": 1}'], "unknown env_kwargs key 'bogus'"),
        (["--env-kwargs", '{"frame_skip": 0}'], "unknown env_kwargs key 'frame_skip'"),
        (["--env-kwargs", '{"robot_noise_ratio": 1e300}'], "'robot_noise_ratio' must be a"),
        (["--env-kwargs", '{"object_noise_ratio": -1}'], "'object_noise_ratio' must be a"),
        (["--env-kwargs", '{"object_noise_ratio": "x"}'], "'object_noise_ratio' must be a"),
        (["--env-kwargs", '{"object_noise_ratio": NaN}'], "NaN is not a JSON number"),
        (["--env-kwargs", '{"object_noise_ratio": Infinity}'], "Infinity is not a JSON"),
        (["--env-kwargs", '{"remove_task_when_completed": 1}'], "must be true or false"),
        (["--env-kwargs", '{"tasks_to_complete": []}'], "env_kwargs may not set"),
        (["--env-kwargs", '{"max_episode_steps": 5}'], "env_kwargs may not set"),
        (["--tasks", "bogus"], "--tasks: benchmark"),
        (["--set", "bogus"], "--set: benchmark: unknown goal set 'bogus'"),
        (["--tasks", "kettle", "--set", "kitchen-mixed"], "--tasks and --set exclude each other"),
    ],
)
def test_bad_benchmark_options_exit_2_with_nothing_run(
    extra, message, capsys, tmp_path, monkeypatch
) -> None:
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path))
    monkeypatch.chdir(tmp_path)
    try:
        code = osg(["--domain", "franka-kitchen", "evaluate", "benchmark", *extra])
    except SystemExit as stop:  # argparse's own refusal of an option's value
        code = stop.code
    assert code == 2
    captured = capsys.readouterr()
    assert message in captured.err and captured.out == ""
    assert "internal error" not in captured.err and not any(tmp_path.iterdir())


@pytest.mark.slow
def test_the_benchmark_json_names_its_perception_and_the_env_options(capsys) -> None:
    argv = ["--domain", "franka-kitchen", "evaluate", "benchmark", "--episodes", "1",
            "--workers", "1", "--env-kwargs", '{"robot_noise_ratio": 0.01}', "--json"]  # fmt: skip
    assert osg(argv) == 0
    import json

    summary = json.loads(capsys.readouterr().out)
    assert summary["perception"]["name"] == "env" and summary["oracle"] is False
    assert summary["env_kwargs"] == {"robot_noise_ratio": 0.01}
    assert summary["max_steps"] <= 280
