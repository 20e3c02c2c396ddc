"""Outputs: nothing is written into the package, destinations are checked before long work,
file-system errors are named, files get the umask's mode, MuJoCo leaves no log file."""

from __future__ import annotations

import hashlib
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from osg_control.classifier.model import SIDECAR_FILE, WEIGHTS_FILE
from osg_control.cli import main
from osg_control.data.datasets import write_episodes
from osg_control.domain.registry import get_domain
from osg_control.errors import EXIT_CODES, OutputError
from osg_control.io_safety import atomic_write, check_output_dir
from osg_control.paths import PACKAGE_DIR
from tests.datagen import WORLD_FIELDS, synthetic_episode
from tests.test_classifier import write_movement_datasets

KITCHEN = get_domain("kitchen")
KITCHEN_DEFAULTS = KITCHEN.defaults_dir
assert KITCHEN_DEFAULTS is not None


def _tree_hashes(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def test_classifier_train_default_goes_to_cache_not_package(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path))
    write_movement_datasets(tmp_path / "kitchen" / "data")
    shipped = _tree_hashes(KITCHEN_DEFAULTS)
    assert not (tmp_path / "kitchen" / "classifier").exists()
    assert main(["classifier", "train", "--epochs", "1", "--json"]) == 0
    capsys.readouterr()
    assert (tmp_path / "kitchen" / "classifier" / SIDECAR_FILE).is_file()
    assert (tmp_path / "kitchen" / "classifier" / WEIGHTS_FILE).is_file()
    assert _tree_hashes(KITCHEN_DEFAULTS) == shipped


def test_no_writer_accepts_a_path_inside_the_package(tmp_path):
    with pytest.raises(OutputError, match="inside the installed package"):
        atomic_write(KITCHEN_DEFAULTS / "classifier" / "x.json", lambda tmp: tmp.write_text("{}"))
    with pytest.raises(OutputError, match="inside the installed package"):
        check_output_dir(PACKAGE_DIR / "kitchen")
    assert not (KITCHEN_DEFAULTS / "classifier" / "x.json").exists()


def test_classifier_train_into_package_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path))
    write_movement_datasets(tmp_path / "kitchen" / "data")
    out = KITCHEN_DEFAULTS / "classifier"
    assert main(["classifier", "train", "--epochs", "1", "--out", str(out)]) == 1
    assert "inside the installed package" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv",
    [
        ["train", "--skill", "grab-cube", "--steps", "100000"],
        ["collect", "--skill", "grab-cube", "--episodes", "1000"],
        ["classifier", "train"],
        ["reproduce", "--quick"],
        ["evaluate", "tasks", "--episodes", "100"],
    ],
)
def test_unwritable_output_is_refused_before_the_work(
    argv, tmp_path, monkeypatch, capsys, no_physics
):
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path))
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    out = blocker / "sub"  # cannot be created, even by root
    if argv[0] == "evaluate":  # its output is the resume cache under $OSG_CACHE_DIR
        monkeypatch.setenv("OSG_CACHE_DIR", str(out))
    else:
        argv = [*argv, "--out", str(out)]
    assert main(argv) == EXIT_CODES["failure"]
    err = capsys.readouterr().err
    assert str(out) in err and "Traceback" not in err


def test_atomic_write_os_error_is_named(tmp_path):
    target = tmp_path / "out.bin"

    def failing(_tmp: Path) -> None:
        raise OSError(28, "No space left on device")

    with pytest.raises(OutputError, match=r"out\.bin: cannot write \(No space left on device\)"):
        atomic_write(target, failing)
    assert not target.exists() and not list(tmp_path.iterdir())


def test_files_get_the_umask_mode(tmp_path):
    previous = os.umask(0o022)
    try:
        path = tmp_path / "d.h5"
        write_episodes(
            path,
            [synthetic_episode()],
            {"skill": "{}", "seed": 0, "world_fields": ",".join(WORLD_FIELDS)},
        )
        assert stat.S_IMODE(path.stat().st_mode) == 0o644
        os.umask(0o002)
        atomic_write(tmp_path / "t.txt", lambda tmp: tmp.write_text("x"))
        assert stat.S_IMODE((tmp_path / "t.txt").stat().st_mode) == 0o664
    finally:
        os.umask(previous)


@pytest.mark.slow
def test_model_build_prints_nothing_and_leaves_no_mujoco_log(tmp_path):
    code = "from osg_control.kitchen.env import KitchenEnv; KitchenEnv().reset(seed=0)"
    env = {**os.environ, "PYTHONPATH": str(Path.cwd())}
    done = subprocess.run(
        [sys.executable, "-c", code],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    assert "empty prefix" not in done.stdout + done.stderr
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
