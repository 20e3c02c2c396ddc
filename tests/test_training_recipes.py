"""A skill's training recipe (``Domain.training``) is declared once and used by every
stage that makes its weights: collection (``osg collect``, ``osg reproduce``) and training
(``osg train``, ``osg reproduce``)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from osg_control.domain.registry import get_domain
from osg_control.domain.spec import TrainingRecipe
from osg_control.errors import DomainError
from osg_control.pipeline.collect import collect_datasets, skill_episodes
from osg_control.pipeline.train import train_skills

PLAIN = "move-home-to-cube"


def test_the_kitchen_declares_its_two_retrained_skills() -> None:
    kitchen = get_domain("kitchen")
    assert kitchen.recipe("grab-cube") == TrainingRecipe(episodes_factor=2, obs_noise=0.01)
    assert kitchen.recipe("push-valve-open") == TrainingRecipe(obs_noise=0.02)
    assert kitchen.recipe(PLAIN) == TrainingRecipe()
    assert skill_episodes(kitchen, kitchen.skill("grab-cube"), 300) == 600
    two_cubes = get_domain("kitchen[cube=2]")
    assert two_cubes.recipe("grab-cube") == kitchen.recipe("grab-cube")


@pytest.mark.parametrize(
    "bad", [{"episodes_factor": 0}, {"episodes_factor": 1.5}, {"obs_noise": -0.01},
            {"obs_noise": float("nan")}],
)  # fmt: skip
def test_a_bad_recipe_is_refused(bad: dict[str, float]) -> None:
    with pytest.raises(ValueError, match=next(iter(bad))):
        TrainingRecipe(**bad)  # type: ignore[arg-type]


def test_a_recipe_for_an_unknown_skill_is_refused() -> None:
    kitchen = get_domain("kitchen")
    with pytest.raises(DomainError, match=r"field 'training' names unknown skills \['grab-cup'\]"):
        dataclasses.replace(kitchen, training={"grab-cup": TrainingRecipe(obs_noise=0.01)})


def test_collection_and_training_follow_the_recipe(tmp_path: Path) -> None:
    """Collected: grab-cube twice the run's episodes; trained: its recipe's noise, recorded
    in its sidecar, the other skill none; an explicit noise applies to every skill."""
    kitchen = get_domain("kitchen")
    sets = collect_datasets(kitchen, tmp_path / "data", 4, seed=0, workers=1,
                            skills=["grab-cube", PLAIN], progress=False)  # fmt: skip
    assert {row["skill"]: row["episodes"] for row in sets.summaries} == {
        "grab-cube": 8, PLAIN: 4,
    }  # fmt: skip
    names = ["grab-cube", PLAIN]
    for out, noise, expected in (("a", None, (0.01, 0.0)), ("b", 0.005, (0.005, 0.005))):
        train_skills(kitchen, tmp_path / "data", tmp_path / out, names, 2, 0, obs_noise=noise)
        recorded = [
            json.loads((tmp_path / out / f"{n}.json").read_text())["train_config"]["obs_noise"]
            for n in names
        ]
        assert tuple(recorded) == expected
