"""Evaluation helpers and the report: start regions, table shapes, Markdown/JSON/plots."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from osg_control.domain.registry import get_domain
from osg_control.errors import PlanningError
from osg_control.evaluation.evaluate import nearest_start_skill
from osg_control.evaluation.report import markdown, write_report
from osg_control.kitchen.paper import PAPER_TABLE_I, PAPER_TASK_AVERAGES, PUBLISHED
from osg_control.kitchen.skills import NODES, SKILLS
from osg_control.kitchen.tasks import TASKS_BY_NAME, get_task

KITCHEN = get_domain("kitchen")


def test_eight_start_regions_four_nodes_four_edge_midpoints() -> None:
    regions = KITCHEN.start_regions
    assert len(regions) == 8
    names = [region.name for region in regions]
    assert names[:4] == ["home", "above-cube", "door-front", "cabinet-front"]
    for name, position in ((r.name, r.position) for r in regions[4:]):
        assert name.startswith("mid(")
        nearest = min(np.linalg.norm(np.subtract(position, n.position)) for n in NODES.values())
        assert nearest > 0.075, f"{name} should lie away from every node"


def test_nearest_start_skill_picks_a_movement_skill_starting_at_the_nearest_node() -> None:
    name = nearest_start_skill(KITCHEN, np.asarray(NODES["door-front"].position) + 0.01)
    assert name == "move-door-to-home"


def test_tasks_match_the_paper_and_one_list_feeds_problems_evaluation_and_report() -> None:
    assert list(TASKS_BY_NAME) == [
        "pick-up", "open-door", "open-pick-up", "pick-up-place", "open-pick-up-place",
        "turn-valve", "open-door-turn-valve", "two-cubes-in-cabinet", "pick-up-cube-2",
    ]  # fmt: skip
    assert list(PAPER_TASK_AVERAGES) == list(TASKS_BY_NAME)[:5]  # the paper's five
    assert "door-open" in get_task("pick-up-place").world
    assert all("door-closed" in get_task(n).world for n in TASKS_BY_NAME if n != "pick-up-place")
    with pytest.raises(PlanningError, match="known tasks: pick-up"):
        get_task("pick-up+place")


def test_report_writes_markdown_json_and_plots(tmp_path: Path) -> None:
    figures = {
        "run": {"command": "osg reproduce --quick"},
        "stage_seconds": {"collect": 1.0},
        "table_i": {
            "noise": [0.0, 0.02],
            "episodes": 4,
            "rows": [{"skill": s.name, "rates": [1.0, 0.5], "scripted": 0.45} for s in SKILLS],
        },
        "table_ii": {"accuracy": 0.7, "corrected_accuracy": 0.9, "num_states": 100},
    }
    written = write_report(figures, tmp_path, PUBLISHED)
    assert json.loads((tmp_path / "figures.json").read_text()) == figures
    text = (tmp_path / "report.md").read_text()
    assert "Table I" in text and "0.927" in text
    report = markdown(figures, PUBLISHED)
    slide_row = next(line for line in report.splitlines() if "| slide-door-open |" in line)
    assert "/".join(map(str, PAPER_TABLE_I["slide-door-open"])) in slide_row
    release_row = next(line for line in report.splitlines() if "| release-cube |" in line)
    assert release_row.rstrip().endswith("| — |")  # split off: the paper has no such row
    assert (tmp_path / "table_i.png").stat().st_size > 1000
    assert (tmp_path / "table_ii.png").stat().st_size > 1000
    assert len(written) == 4  # report, figures and a plot per table
