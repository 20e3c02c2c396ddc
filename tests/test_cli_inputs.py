"""Every CLI value is checked before any work: a bad one exits 2 with a message naming the
option and no traceback; errors of any kind end as one line and a documented exit code."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from osg_control import cli
from osg_control.errors import EXIT_CODES, OutputError

BAD_VALUES = [
    (["run", "--goal", ""], "--goal"),
    (["run", "--goal", "   "], "--goal"),
    (["run", "--goal", "door-open", "--episodes", "0"], "--episodes"),
    (["run", "--goal", "door-open", "--noise", "-0.1"], "--noise"),
    (["run", "--goal", "door-open", "--noise", "nan"], "--noise"),
    (["run", "--goal", "door-open", "--max-replans", "-1"], "--max-replans"),
    (["run", "--goal", "door-open", "--seed", "-1"], "--seed"),
    (["run", "--goal", "door-open", "--filter", "0"], "--filter"),
    (["run", "--goal", "door-open", "--filter", "1.5"], "--filter"),
    (["run", "--goal", "door-open", "--filter", "nan"], "--filter"),
    (["run", "--goal", "door-open", "--facts", "door-ajar"], "--facts"),
    (["run", "--goal", "door-opn"], "--goal"),
    (["--domain", "attic", "plan", "--goal", "door-open"], "--domain"),
    (["run", "--goal", "door-open", "--start", "nowhere"], "--start"),
    (["evaluate", "tasks", "--replans", "0", "-1"], "--replans"),
    (["evaluate", "tasks", "--workers", "0"], "--workers"),
    (["eval-skills", "--noise", "0.01", "inf"], "--noise"),
    (["collect", "--workers", "0"], "--workers"),
    (["collect", "--episodes", "-3"], "--episodes"),
    (["classifier", "reach", "--noise", "-1"], "--noise"),
    (["train", "--skill", "grab-cube", "--obs-noise", "-0.01"], "--obs-noise"),
    (["train", "--skill", "grab-cube", "--obs-noise", "nan"], "--obs-noise"),
    (["classifier", "train", "--validation-fraction", "1"], "--validation-fraction"),
    (["classifier", "train", "--validation-fraction", "-0.1"], "--validation-fraction"),
    (["classifier", "train", "--validation-fraction", "nan"], "--validation-fraction"),
]


@pytest.mark.parametrize(("argv", "option"), BAD_VALUES)
def test_bad_values_are_refused_before_any_work(
    argv, option, capsys, tmp_path, monkeypatch, no_physics
):
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path))
    assert cli.main(argv) == EXIT_CODES["usage"]
    err = capsys.readouterr().err
    assert err.startswith("osg: error: ") and option in err
    assert "Traceback" not in err
    assert not any(tmp_path.iterdir())  # nothing written


@pytest.mark.slow
def test_video_without_gl_backend_is_a_usage_error(tmp_path):
    env = {**os.environ, "MUJOCO_GL": "glfw", "DISPLAY": "", "OSG_CACHE_DIR": str(tmp_path)}
    env.pop("DISPLAY")
    argv = ["run", "--goal", "door-open", "--video", str(tmp_path / "v.mp4")]
    done = subprocess.run(
        [sys.executable, "-m", "osg_control.cli", *argv],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == EXIT_CODES["usage"], done.stderr
    assert "--video" in done.stderr and "MUJOCO_GL" in done.stderr
    assert "Traceback" not in done.stderr


def _failing_command(exc: BaseException):
    def func(_args):
        raise exc

    return func


@pytest.mark.parametrize(
    ("exc", "code", "text"),
    [
        (OutputError("/x: cannot write"), EXIT_CODES["failure"], "/x: cannot write"),
        (PermissionError(13, "Permission denied", "/y"), EXIT_CODES["failure"], "/y"),
        (ZeroDivisionError("boom"), EXIT_CODES["failure"], "internal error"),
        (KeyboardInterrupt(), EXIT_CODES["interrupted"], "interrupted"),
    ],
)
def test_top_level_handler_maps_errors_to_codes(exc, code, text, capsys, monkeypatch):
    parser = cli.build_parser()
    original = parser.parse_args

    def parse(argv):
        args = original(argv)
        args.func = _failing_command(exc)
        return args

    monkeypatch.setattr(cli, "build_parser", lambda modules=None: parser)
    monkeypatch.setattr(parser, "parse_args", parse)
    assert cli.main(["graph"]) == code
    err = capsys.readouterr().err
    assert text in err and "Traceback" not in err
    assert cli.main(["--debug", "graph"]) == code
    assert "Traceback" in capsys.readouterr().err or code == EXIT_CODES["interrupted"]


@pytest.mark.slow
def test_sigterm_is_handled_like_ctrl_c(tmp_path):
    env = {**os.environ, "OSG_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(Path.cwd())}
    argv = ["collect", "--skill", "grab-cube", "--episodes", "2000", "--workers", "1"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "osg_control.cli", *argv],
        env=env,
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
    )
    deadline = time.monotonic() + 60
    parts = tmp_path / "kitchen" / "data" / ".parts" / "grab-cube"
    while not list(parts.glob("*.h5")) and time.monotonic() < deadline:
        time.sleep(0.1)  # collection is under way (its first chunk is written)
    proc.send_signal(signal.SIGTERM)
    _out, err = proc.communicate(timeout=60)
    assert proc.returncode == EXIT_CODES["interrupted"], err
    assert "osg: interrupted" in err and "Traceback" not in err
    assert list(parts.glob("*.h5"))  # the finished chunks are kept for a resume


def test_run_names_the_models_it_uses(capsys, tmp_path, monkeypatch):
    import json

    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path))
    assert cli.main(["run", "--goal", "door-closed", "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["models"]["source"] == "shipped defaults"
    assert payload["models"]["skills"].endswith("defaults/skills")
    assert cli.main(["run", "--goal", "door-closed"]) == 0
    assert capsys.readouterr().out.startswith("models: ")
