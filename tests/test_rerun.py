"""``osg run --rerun``: a short run's recording verifies with rerun's own tool and holds
every entity, headless (nothing under the home folder); without rerun-sdk, exit 2 naming
the extra."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from osg_control.cli import main
from osg_control.errors import EXIT_CODES

RUN = ["run", "--goal", "door-open", "--episodes", "2", "--seed", "1"]
ENTITIES = (
    "nodes",
    "target",
    "tcp",
    "path",
    "joints",
    "gripper/command",
    "gripper/force",
    "gripper/width",
    "skill",
    "plan",
    "events",
)


def _rerun_cli(args: list[str], home: Path) -> subprocess.CompletedProcess[str]:
    """The ``rerun`` command line in a home folder of its own, its analytics disabled."""
    rerun = shutil.which("rerun", path=os.path.dirname(sys.executable)) or shutil.which("rerun")
    if rerun is None:
        pytest.skip("rerun-sdk installs no `rerun` command here")
    env = {**os.environ, "HOME": str(home)}
    subprocess.run([rerun, "analytics", "disable"], env=env, capture_output=True, check=True)
    return subprocess.run(
        [rerun, *args], check=False, env=env, capture_output=True, text=True, timeout=120
    )


def test_a_run_writes_a_recording_rerun_verifies(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("rerun", reason="rerun-sdk (the [viz] extra) is not installed")
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    path = tmp_path / "run.rrd"
    assert main([*RUN, "--rerun", str(path), "--video", str(tmp_path / "run.mp4")]) == 0
    assert f"rerun recording written to {path}" in capsys.readouterr().out
    assert path.stat().st_size > 10_000
    assert list(home.rglob("*")) == [], "the SDK wrote under the home folder"

    verified = _rerun_cli(["rrd", "verify", str(path)], tmp_path / "cli-home")
    assert verified.returncode == 0, verified.stderr
    printed = _rerun_cli(["rrd", "print", str(path)], tmp_path / "cli-home")
    assert printed.returncode == 0, printed.stderr
    for episode in (0, 1):
        for entity in ENTITIES:
            assert f"episode_{episode}/{entity}" in printed.stdout, (episode, entity)
    assert "episode_0/camera" in printed.stdout and "episode_1/camera" not in printed.stdout


def test_without_the_extra_it_exits_2_naming_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "rerun", None)  # import rerun raises ImportError
    path = tmp_path / "run.rrd"
    assert main([*RUN, "--rerun", str(path)]) == EXIT_CODES["usage"]
    err = capsys.readouterr().err
    assert "--rerun needs rerun-sdk" in err and "osg-control[viz]" in err
    assert not path.exists()


def test_a_file_name_without_rrd_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([*RUN, "--rerun", str(tmp_path / "run.mp4")]) == EXIT_CODES["usage"]
    assert "must end in .rrd" in capsys.readouterr().err
