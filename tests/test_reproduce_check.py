"""``osg reproduce --check``: figures agree with the shipped ones within their intervals."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from osg_control.cli import main
from osg_control.errors import DatasetError
from osg_control.evaluation.check import (
    MIN_TRIALS,
    cells,
    compare,
    detectable_difference,
    wilson_interval,
)
from osg_control.execution import defaults

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
    same = compare(FIGURES, FIGURES)
    assert (same.compared, same.mismatches) == (5, [])
    nearby = copy.deepcopy(FIGURES)
    nearby["table_i"]["rows"][0]["rates"][1] = 0.86  # 200 trials: within sampling noise
    assert compare(FIGURES, nearby).mismatches == []
    far = copy.deepcopy(FIGURES)
    far["tables_iv_v"]["rates"][1][0][0] = 0.5
    result = compare(FIGURES, far)
    assert result.compared == 5
    assert [m.where for m in result.mismatches] == ["Tables IV/V replans=2 t r"]


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


def _with_trials(
    figures: dict, trials: int | None, rate: float | None = None, only: str | None = None
) -> dict:
    """``figures`` with every table's (or table ``only``'s) trial count set to ``trials``
    (None: kept) and, given ``rate``, every rate set to it."""
    out = copy.deepcopy(figures)
    for key, table in out.items():
        if not isinstance(table, dict) or only not in (None, key):
            continue
        for count in ("episodes", "num_states"):
            if count in table and trials is not None:
                table[count] = trials
        if rate is None:
            continue
        if key == "table_i":
            for row in table["rows"]:
                row["rates"] = [rate] * len(row["rates"])
        elif key == "table_ii":
            table["accuracy"] = table["corrected_accuracy"] = rate
        elif key == "table_iii":
            for row in table["rows"]:
                row["success"] = rate
        elif key == "tables_iv_v":
            table["rates"] = [[[rate] * len(r) for r in t] for t in table["rates"]]
    return out


SHIPPED = json.loads(
    (Path(__file__).resolve().parents[1] / "osg_control/kitchen/defaults/figures.json").read_text()
)


@pytest.mark.parametrize(
    ("trials", "rate", "only", "fragment"),
    [
        (1, 1.0, None, "fewer trials than the shipped cell's"),
        (2, 0.9, None, "fewer trials than the shipped cell's"),
        (1, 0.9, None, "(1 < 200)"),
        (2, 1.0, None, "179 cells have fewer trials"),
        (1, 1.0, "table_ii", "Table II accuracy (1 < 8186)"),
        (99, None, "tables_iv_v", "112 cells have fewer trials"),
    ],
)
def test_a_comparison_without_the_power_to_find_a_difference_is_refused(
    trials: int,
    rate: float | None,
    only: str | None,
    fragment: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    report = tmp_path / "figures.json"
    report.write_text(json.dumps(_with_trials(SHIPPED, trials, rate, only)))
    before = report.read_bytes()
    assert main(["reproduce", "--compare", str(report)]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""  # no verdict printed: the comparison was refused
    assert captured.err.startswith(f"osg: error: {report}: ") and fragment in captured.err
    assert "power" in captured.err and report.read_bytes() == before


def test_shipped_figures_with_too_few_trials_are_refused_as_a_reference(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    shipped = tmp_path / "shipped"
    shipped.mkdir()
    (shipped / "figures.json").write_text(json.dumps(_with_trials(SHIPPED, 2, 1.0)))
    (tmp_path / "figures.json").write_text(json.dumps(SHIPPED))
    monkeypatch.setattr(defaults, "defaults_root", lambda domain, directory=None: shipped)
    assert main(["reproduce", "--compare", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert f"fewer than {MIN_TRIALS} trials" in err and str(shipped / "figures.json") in err


def test_the_detectable_difference_is_reported_per_cell_and_overall(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "figures.json").write_text(json.dumps(SHIPPED))
    assert main(["reproduce", "--compare", str(tmp_path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    power = out["detectable_difference"]
    assert out["compared"] == len(power["cells"]) == 179
    assert 0 < power["smallest"] <= power["median"] <= power["largest"] < 0.25
    assert power["cells"][power["largest_at"]] == power["largest"]
    assert main(["reproduce", "--compare", str(tmp_path)]) == 0
    assert "smallest difference it could detect, per cell: 0.0" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("rate", "shipped", "trials"),
    [(0.5, 100, 100), (0.9, 200, 200), (1.0, 200, 400), (0.0, 50, 30)],
)
def test_the_detectable_difference_is_the_edge_of_disjoint_intervals(
    rate: float, shipped: int, trials: int
) -> None:
    d = detectable_difference(rate, shipped, trials)
    assert d is not None and 0 < d < 0.5
    low, high = wilson_interval(rate, shipped)
    edges = [wilson_interval(m, trials) for m in (rate + d, rate - d) if 0.0 <= m <= 1.0]
    assert any(b[0] > high - 1e-9 or b[1] < low + 1e-9 for b in edges)  # disjoint at d
    nearer = (rate + 0.99 * d, rate - 0.99 * d)
    inside = [wilson_interval(r, trials) for r in nearer if 0.0 <= r <= 1.0]
    assert all(b[0] <= high and b[1] >= low for b in inside)
    assert detectable_difference(0.5, 1, 1) is None  # one trial each: nothing is ever outside


def test_a_genuinely_different_result_is_still_reported_outside(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "figures.json").write_text(json.dumps(_with_trials(SHIPPED, None, 0.3)))
    assert main(["reproduce", "--compare", str(tmp_path)]) == 1
    out = capsys.readouterr().out
    assert "179 cells compared" in out and "0 outside" not in out


def test_check_with_quick_is_a_usage_error(tmp_path: Path) -> None:
    assert main(["reproduce", "--quick", "--check", "--out", str(tmp_path / "r")]) == 2
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize(("rate", "code"), [(None, 0), (0.3, 1)])
def test_check_with_json_prints_one_document(
    rate: float | None,
    code: int,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``reproduce --check --json``: stdout is one JSON document, the figures with the
    verdict under ``check``; the stages' text goes to stderr. The pipeline is replaced by
    one that logs and returns figures (the shipped ones, or every rate at ``rate``)."""
    from osg_control.pipeline import reproduction

    figures = _with_trials(SHIPPED, None, rate)

    def fake_reproduce(config: Any, log: Any) -> Any:
        log("== collect")
        return SimpleNamespace(
            figures=figures, out=tmp_path, report=[tmp_path / "report.md"], stage_seconds={}
        )

    monkeypatch.setattr(reproduction, "reproduce", fake_reproduce)
    argv = ["reproduce", "--check", "--json", "--out", str(tmp_path / "r")]
    assert main(argv) == code
    captured = capsys.readouterr()
    document = json.loads(captured.out)  # one document: a second would be "Extra data"
    assert {key: document[key] for key in figures} == figures
    assert document["check"]["compared"] == 179
    assert len(document["check"]["mismatches"]) == (0 if rate is None else 179)
    assert "== collect" in captured.err and "== collect" not in captured.out
    assert main(argv[:2] + argv[3:]) == code  # in words: the figures' files, then the verdict
    assert "check: 179 cells compared" in capsys.readouterr().out
