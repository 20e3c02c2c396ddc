"""Offline learning on real kitchen data: a trained skill beats the script that made its data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.stats import fisher_exact

from osg_control.cli import main
from osg_control.data.collect import collect_skill, run_scripted_episode
from osg_control.domain.registry import get_domain
from osg_control.evaluation.skill_table import SkillEpisode, run_skill_episode
from osg_control.kitchen.skills import get_skill
from osg_control.perception.spec import PerceptionSpec

KITCHEN = get_domain("kitchen")

SKILL = "move-home-to-door"
EPISODES = 40


@pytest.mark.slow
def test_trained_skill_beats_its_scripted_policy(tmp_path: Path) -> None:
    data = tmp_path / "data"
    collect_skill(KITCHEN, SKILL, 60, 0, data, None, False)
    out = tmp_path / "skills"
    argv = ["train", "--skill", SKILL, "--steps", "1500", "--data", str(data), "--out", str(out)]
    assert main([*argv, "--threads", "1", "--seed", "0"]) == 0
    learned = [
        run_skill_episode(SkillEpisode("kitchen", SKILL, str(out), PerceptionSpec(), 7, 0, i))
        for i in range(EPISODES)
    ]
    scripted = [
        run_scripted_episode(KITCHEN, get_skill(SKILL), 7, i).success for i in range(EPISODES)
    ]
    table = [[sum(learned), EPISODES - sum(learned)], [sum(scripted), EPISODES - sum(scripted)]]
    _odds, p_value = fisher_exact(table, alternative="greater")
    assert np.mean(learned) > np.mean(scripted) and p_value < 0.01, table
