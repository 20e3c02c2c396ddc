"""``osg reproduce``'s own output: the manifest's command reproduces the run with the robot
``--robot`` chose, and ``--json`` leaves stdout to the JSON (the stages' text on stderr)."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from osg_control import cli
from osg_control.commands.reproduce import manifest_command
from osg_control.domain.registry import get_domain
from osg_control.pipeline import reproduction


def test_the_manifest_command_names_a_chosen_robot() -> None:
    parser = cli.build_parser(["reproduce"])
    args = parser.parse_args(["--robot", "ur5", "reproduce", "--quick", "--out", "x"])
    kitchen = get_domain("kitchen")
    ur5 = manifest_command(kitchen.with_robot("ur5"), args)
    assert ur5 == "osg --domain kitchen --robot ur5 reproduce --quick --seed 0 --out x"
    assert manifest_command(kitchen, args).startswith("osg --domain kitchen reproduce --quick")


def test_json_stdout_is_the_figures_alone(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The pipeline itself runs in ``test_pipeline.py``; here only where its text goes."""
    seen: list[Any] = []

    def stages(config: reproduction.ReproduceConfig, log: Any) -> SimpleNamespace:
        seen.append(config)
        log("== collect\nskill  episodes")
        return SimpleNamespace(figures={"quick": True}, out=config.out)

    monkeypatch.setattr(reproduction, "reproduce", stages)
    argv = ["--robot", "ur5", "reproduce", "--quick", "--out", str(tmp_path), "--json"]
    assert cli.main(argv) == 0
    out, err = capsys.readouterr()
    assert json.loads(out) == {"quick": True}
    assert "== collect" in err
    (config,) = seen
    assert config.domain.ref == "kitchen@ur5" and "--robot ur5" in config.command
