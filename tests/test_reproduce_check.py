"""``osg reproduce --check``: figures agree with the shipped ones within their intervals."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from osg_control.cli import main
from osg_control.errors import DatasetError
from osg_control.evaluation.check import cells, compare, wilson_interval

FIGURES = {
    "table_i": {
        "noise": [0.0, 0.02],
        "episodes": 200,
        "rows": [{"skill": "a", "rates": [1.0, 0.9], "scripted": 0.45}],
    },
    "table_iii": {"episodes": 200, "rows": [{"start": "r", "success": 0.99}]},
    "tables_iv_v": {
        "episodes": 100,
        "replans": [0, 2],
        "tasks": ["t"],
        "regions": ["r"],
        "rates": [[[0.8]], [[0.9]]],
    },
}


def test_wilson_interval_brackets_the_rate_and_narrows_with_trials() -> None:
    low, high = wilson_interval(0.9, 100)
    assert low < 0.9 < high
    wide, narrow = wilson_interval(0.5, 20), wilson_interval(0.5, 2000)
    assert narrow[1] - narrow[0] < (wide[1] - wide[0]) / 5
    assert wilson_interval(1.0, 200)[1] == 1.0 and wilson_interval(1.0, 200)[0] > 0.95


def test_identical_and_nearby_figures_agree_far_ones_do_not() -> None:
    assert len(list(cells(FIGURES))) == 2 + 1 + 2
    assert compare(FIGURES, FIGURES) == (5, [])
    nearby = copy.deepcopy(FIGURES)
    nearby["table_i"]["rows"][0]["rates"][1] = 0.86  # 200 trials: within sampling noise
    assert compare(FIGURES, nearby)[1] == []
    far = copy.deepcopy(FIGURES)
    far["tables_iv_v"]["rates"][1][0][0] = 0.5
    compared, mismatches = compare(FIGURES, far)
    assert compared == 5 and [m.where for m in mismatches] == ["Tables IV/V replans=2 t r"]


def test_reports_without_a_shared_cell_are_refused() -> None:
    with pytest.raises(DatasetError, match="share no table cell"):
        compare(
            FIGURES, {"table_ii": {"accuracy": 0.8, "corrected_accuracy": 0.9, "num_states": 10}}
        )


def test_cli_compares_a_report_with_the_shipped_figures(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    shipped = json.loads(
        (
            Path(__file__).resolve().parents[1] / "osg_control/kitchen/defaults/figures.json"
        ).read_text()
    )
    (tmp_path / "figures.json").write_text(json.dumps(shipped))
    assert main(["reproduce", "--compare", str(tmp_path)]) == 0
    assert "0 outside the intervals" in capsys.readouterr().out
    shipped["table_iii"]["rows"][0]["success"] = 0.5
    (tmp_path / "figures.json").write_text(json.dumps(shipped))
    assert main(["reproduce", "--compare", str(tmp_path / "figures.json")]) == 1
    assert "Table III" in capsys.readouterr().out
