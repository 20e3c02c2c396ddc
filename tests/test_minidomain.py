"""A second domain end to end through the generic core (the worked example of docs/domains.md).

``tests/minidomain`` is written the way a user would write a domain in their own project: it
is registered here at run time, then collected (Algorithm 1), trained (``osg train``, a short
run), classified, turned into a graph and PDDL, planned for and executed, with nothing of the
kitchen imported.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from minidomain import DOMAIN_NAME, mini_domain

from osg_control import cli
from osg_control.classifier.data import load_classifier_data, movement_classes
from osg_control.classifier.model import StateClassifier
from osg_control.classifier.train import TrainConfig, train_classifier
from osg_control.data.collect import collect_skill
from osg_control.data.datasets import load_dataset
from osg_control.domain.base import Domain
from osg_control.domain.registry import domain_names, get_domain, register_domain
from osg_control.execution.executor import Executor
from osg_control.learning.policy import load_policies
from osg_control.planning.api import plan_for_goal
from osg_control.planning.graph import graph_from_specs
from osg_control.planning.graph_data import graph_from_datasets
from osg_control.planning.pddl_io import export_pddl
from osg_control.planning.pddl_parse import read_domain, read_problem

EPISODES = 24
"""Scripted episodes per skill (under a second each skill)."""
TRAIN_STEPS = 2000
"""TD3+BC updates (all three skills batched; a few seconds on one thread)."""
PLAN = ["move-home-to-button", "press-button"]
GOAL = ["button-pressed"]


@pytest.fixture(scope="module")
def domain() -> Domain:
    register_domain(DOMAIN_NAME, mini_domain)
    return get_domain(DOMAIN_NAME)


@pytest.fixture(scope="module")
def trained(domain: Domain, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A defaults-style folder: ``data/``, ``skills/`` and ``classifier/``."""
    root = tmp_path_factory.mktemp("mini")
    for skill in domain.skills:
        dataset = collect_skill(domain, skill, EPISODES, seed=0, out=root / "data", progress=False)
        assert dataset.num_episodes == EPISODES
        assert dataset.episode_successes.all(), f"{skill.name}: the script must not fail"
    argv = ["--domain", DOMAIN_NAME, "train", "--skill", "all", "--steps", str(TRAIN_STEPS)]
    argv += ["--data", str(root / "data"), "--out", str(root / "skills"), "--threads", "1"]
    assert cli.main(argv) == 0
    classes = movement_classes(domain)
    data = load_classifier_data(root / "data", classes, seed=0)
    train_classifier(data, TrainConfig(epochs=30, batch_size=128, validation_fraction=0.0)).save(
        root / "classifier"
    )
    return root


def test_registered_domain_is_listed(domain: Domain, capsys: pytest.CaptureFixture[str]) -> None:
    assert DOMAIN_NAME in domain_names()
    assert cli.main(["--domain", DOMAIN_NAME, "domains", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    mini = next(d for d in listed if d["name"] == DOMAIN_NAME)
    assert [s["name"] for s in mini["skills"]] == [s.name for s in domain.skills]


@pytest.mark.slow
def test_graph_and_pddl_from_data(domain: Domain, trained: Path, tmp_path: Path) -> None:
    datasets = [load_dataset(trained / "data" / f"{s.name}.h5") for s in domain.skills]
    graph = graph_from_datasets(domain, datasets)
    assert graph.disagreements == ()  # the data's regions and effects are the specs'
    observed = graph.edge("press-button").observed
    assert observed is not None
    assert (observed.add, observed.delete) == (("button-pressed",), ("button-up",))

    paths = export_pddl(domain, tmp_path, graph)
    assert [p.relative_to(tmp_path).as_posix() for p in paths] == [
        f"osg-{DOMAIN_NAME}.pddl",
        "problems/press.pddl",
    ]
    pddl = read_domain(paths[0])
    assert {a.name for a in pddl.actions} == {s.name for s in domain.skills}
    read_problem(paths[1])


def test_plan(domain: Domain, capsys: pytest.CaptureFixture[str]) -> None:
    result = plan_for_goal(domain, GOAL)
    assert result.solved and list(result.actions) == PLAN
    assert list(plan_for_goal(domain, GOAL, node="above-button").actions) == PLAN[1:]
    assert plan_for_goal(domain, GOAL, world=["hand-empty", "button-pressed"]).actions == ()
    assert cli.main(["--domain", DOMAIN_NAME, "plan", "--goal", " ".join(GOAL), "--json"]) == 0
    steps = json.loads(capsys.readouterr().out)["steps"]
    assert [step["action"] for step in steps] == PLAN


@pytest.mark.slow
def test_classifier_tells_the_movement_starts_apart(domain: Domain, trained: Path) -> None:
    classifier = StateClassifier.load(trained / "classifier", movement_classes(domain))
    env = domain.make_env()
    for node, expected in (
        ("home", "move-home-to-button"),
        ("above-button", "move-button-to-home"),
    ):
        obs, _ = env.reset(seed=0, options={"node": node})
        assert classifier.predict(obs) == expected


@pytest.mark.slow
def test_execute_reaches_the_goal(domain: Domain, trained: Path) -> None:
    classifier = StateClassifier.load(trained / "classifier", movement_classes(domain))
    policies = load_policies(trained / "skills")
    executor = Executor(domain, policies, classifier, graph_from_specs(domain))
    env = domain.make_env()
    obs, _ = env.reset(seed=0)
    assert "button-up" in env.facts()
    result = executor.execute(GOAL, env, obs)
    assert result.plan == PLAN and result.entry_skill is None
    assert result.success, result.failure
    assert [o.skill for o in result.outcomes] == PLAN and result.replans == 0
    assert set(GOAL) <= env.facts()
    assert np.linalg.norm(env.tcp_pose()[0] - domain.nodes["button-down"].position) < 0.02


@pytest.mark.slow
def test_cli_run(trained: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["--domain", DOMAIN_NAME, "run", "--goal", " ".join(GOAL), "--start", "home"]
    assert cli.main([*argv, "--models", str(trained), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["success_rate"] == 1.0 and report["episodes"][0]["plan"] == PLAN


@pytest.mark.slow
def test_cli_train_stops_each_skill_on_its_held_out_success(
    domain: Domain, trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "skills"
    argv = ["--domain", DOMAIN_NAME, "train", "--skill", "all", "--steps", "900"]
    argv += ["--data", str(trained / "data"), "--out", str(out), "--threads", "1", "--json"]
    argv += ["--early-stop", "--check-every", "300", "--patience", "1", "--check-episodes", "4"]
    argv += ["--workers", "1", "--filter"]
    capsys.readouterr()
    assert cli.main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["skill_updates"] == sum(r["trained_updates"] for r in summary["skills"])
    assert summary["skill_updates"] <= 900 * len(domain.skills) and summary["check_seconds"] > 0
    for row in summary["skills"]:
        checks = row["held_out"]
        assert [u for u, _ in checks] == list(range(300, row["trained_updates"] + 1, 300))
        best = max(rate for _, rate in checks)
        assert row["updates"] == max(u for u, rate in checks if rate == best)  # latest best
        sidecar = json.loads((out / f"{row['skill']}.json").read_text())
        record = sidecar["train_config"]["early_stopping"]
        assert sidecar["steps"] == row["updates"] and record["max_updates"] == 900
        assert record["rule"]["patience"] == 1 and record["rule"]["held_out"]["episodes"] == 4
        assert record["rule"]["held_out"]["filter_gain"] == 0.2
    assert set(load_policies(out)) == {s.name for s in domain.skills}
