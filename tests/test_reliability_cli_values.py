"""Reliability, round 4: command-line values that meant something else, and files whose
values were taken on trust. Each case: the command, its exit code, a message fragment, and
nothing written."""

from __future__ import annotations

import json
import logging
import shutil
from pathlib import Path

import pytest

from osg_control import cli
from osg_control.domain.registry import get_domain
from osg_control.errors import EXIT_CODES, CheckpointError
from osg_control.execution.bundle import success_rates

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "osg_control/kitchen/defaults"

USAGE = [
    (["run", "--goal", "door-open", "--perception", ""], "unknown perception ''"),
    (
        ["--domain", "franka-kitchen", "run", "--goal", "kettle-moved", "--randomize-objects"],
        "--randomize-objects: domain 'franka-kitchen' has no object with a placement region",
    ),
    (
        ["--domain", "franka-kitchen", "evaluate", "tasks", "--randomize-objects"],
        "--randomize-objects: domain 'franka-kitchen' has no object with a placement region",
    ),
]


@pytest.fixture(autouse=True)
def _isolated(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Each command runs in an empty folder with its own cache (to show nothing written)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path / "cache"))


@pytest.mark.parametrize(("argv", "fragment"), USAGE, ids=[" ".join(u[0])[:50] for u in USAGE])
def test_values_that_meant_something_else_exit_2(
    argv: list[str], fragment: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert cli.main(argv) == EXIT_CODES["usage"]
    captured = capsys.readouterr()
    assert fragment in captured.err and "internal error" not in captured.err
    assert captured.out == "" and not any(tmp_path.iterdir())


@pytest.mark.parametrize("rate", [True, False, "0.9", 1.5, -0.1, None])
def test_a_rates_file_holds_rates_only(
    rate: object, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """JSON ``true`` was taken as a success rate of 1.0."""
    rates = tmp_path / "rates.json"
    rates.write_text(json.dumps({"grab-cube": rate}))
    assert cli.main(["graph", "--rates", str(rates)]) == EXIT_CODES["failure"]
    assert "success rate in [0, 1]; not rates" in capsys.readouterr().err


@pytest.mark.parametrize("rate", [True, "1.0"])
def test_a_manifest_rate_that_is_not_a_number_is_refused(rate: object) -> None:
    with pytest.raises(CheckpointError, match="is not in \\[0, 1\\]"):
        success_rates({"success_rates": {"grab-cube": rate}}, Path("m.json"), get_domain("kitchen"))


def test_a_models_folder_without_a_manifest_says_it_plans_at_uniform_costs(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, capsys: pytest.CaptureFixture[str]
) -> None:
    models = tmp_path / "models"
    for part in ("skills", "classifier"):
        shutil.copytree(SHIPPED / part, models / part)
    with caplog.at_level(logging.WARNING):
        assert cli.main(["plan", "--goal", "door-open", "--models", str(models)]) == 0
    assert f"{models}: no manifest.json: planning at uniform skill costs" in caplog.text
    caplog.clear()
    (models / "manifest.json").symlink_to(SHIPPED / "manifest.json")
    with caplog.at_level(logging.WARNING):
        assert cli.main(["plan", "--goal", "door-open", "--models", str(models)]) == 0
    assert "uniform" not in caplog.text
    capsys.readouterr()


def test_an_at_node_goal_is_run_and_scored_on_the_truth(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert cli.main(["run", "--goal", "(at above-valve)", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["success_rate"] == 1.0 and out["episodes"][0]["scored_success"] is True
    assert cli.main(["run", "--goal", "(at nowhere)"]) == EXIT_CODES["usage"]
    assert "--goal: unknown node 'nowhere' in (at nowhere)" in capsys.readouterr().err
