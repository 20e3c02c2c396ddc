"""``osg plan --models DIR``: the plan costs of a defaults folder's measured success rates."""

from __future__ import annotations

import json
from pathlib import Path

from osg_control.cli import main
from osg_control.domain.registry import get_domain

KITCHEN = get_domain("kitchen")


def _plan_json(argv: list[str], capsys) -> dict:
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_plan_costs_follow_the_models_manifest(tmp_path: Path, capsys) -> None:
    manifest = json.loads((KITCHEN.defaults_dir / "manifest.json").read_text())
    manifest["success_rates"] = {name: 0.5 for name in manifest["success_rates"]}
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    (tmp_path / "skills").symlink_to(KITCHEN.defaults_dir / "skills")
    argv = ["plan", "--goal", "cube-lifted", "--json"]
    shipped = _plan_json(argv, capsys)
    halved = _plan_json([*argv, "--models", str(tmp_path)], capsys)
    assert [s["action"] for s in halved["steps"]] == [s["action"] for s in shipped["steps"]]
    assert all(step["cost"] == 693 for step in halved["steps"])  # round(-ln 0.5 * 1000)
    assert halved["cost"] != shipped["cost"]


def test_plan_refuses_both_graph_and_models(tmp_path: Path, capsys) -> None:
    models = str(KITCHEN.defaults_dir)
    argv = [
        "plan",
        "--goal",
        "cube-lifted",
        "--graph",
        str(tmp_path / "g.json"),
        "--models",
        models,
    ]
    assert main(argv) == 2
    assert "--graph and --models" in capsys.readouterr().err
