"""Every writer of ``osg`` on every hostile destination: inside the installed package
(directly and through a symlink), a read-only file system and a full one (small tmpfs
mounts, root only). Each must exit 1 naming the path, print no traceback, and leave every
existing file byte-identical."""

from __future__ import annotations

import contextlib
import hashlib
import subprocess
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from osg_control.cli import main
from osg_control.errors import EXIT_CODES
from osg_control.paths import PACKAGE_DIR
from tests.datagen import chained_dataset
from tests.filesystems import tmpfs

SHIPPED = PACKAGE_DIR / "kitchen" / "defaults"


def _tree_hashes(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file() and "__pycache__" not in p.parts
    }


def _minari_source(tmp_path: Path) -> Path:
    """A Minari data set made from a tiny project data set (the import's input)."""
    data = chained_dataset(tmp_path / "src" / "grab-cube.h5")
    root = tmp_path / "minari"
    assert (
        main(["datasets", "minari", str(data), "--id", "osg/grab-cube-v0", "--out", str(root)]) == 0
    )
    return root / "osg" / "grab-cube-v0"


def _lerobot_source(tmp_path: Path) -> Path:
    """A LeRobot data set made from a tiny project data set (the import's input)."""
    data = chained_dataset(tmp_path / "src" / "grab-cube.h5")
    assert main(["datasets", "lerobot", str(data), "--out", str(tmp_path / "lerobot")]) == 0
    return tmp_path / "lerobot"


WRITERS: dict[str, Callable[[Path, Path], list[str]]] = {
    "graph --out": lambda dest, tmp: ["graph", "--out", str(dest / "figures.json")],
    "graph --png": lambda dest, tmp: ["graph", "--png", str(dest / "graph.png")],
    "pddl export": lambda dest, tmp: ["pddl", "export", "--out", str(dest)],
    "datasets minari": lambda dest, tmp: [
        "datasets",
        "minari",
        str(chained_dataset(tmp / "data" / "grab-cube.h5")),
        "--id",
        "osg/x-v0",
        "--out",
        str(dest),
    ],
    "datasets import": lambda dest, tmp: [
        "datasets",
        "import",
        str(_minari_source(tmp)),
        "--skill",
        "grab-cube",
        "--out",
        str(dest / "grab-cube.h5"),
    ],
    "datasets lerobot": lambda dest, tmp: [
        "datasets",
        "lerobot",
        str(chained_dataset(tmp / "data" / "grab-cube.h5")),
        "--out",
        str(dest / "lerobot"),
    ],
    "datasets import --layout lerobot": lambda dest, tmp: [
        "datasets",
        "import",
        str(_lerobot_source(tmp)),
        "--layout",
        "lerobot",
        "--skill",
        "grab-cube",
        "--out",
        str(dest / "grab-cube.h5"),
    ],
    "train": lambda dest, tmp: [
        "train",
        "--skill",
        "grab-cube",
        "--steps",
        "100000",
        "--out",
        str(dest),
    ],
    "collect": lambda dest, tmp: [
        "collect",
        "--skill",
        "grab-cube",
        "--episodes",
        "1000",
        "--out",
        str(dest),
    ],
    "classifier train": lambda dest, tmp: ["classifier", "train", "--out", str(dest)],
    "reproduce": lambda dest, tmp: ["reproduce", "--quick", "--out", str(dest)],
}
"""Each writer's command line with its output under ``dest`` (``tmp`` holds its inputs)."""


@contextlib.contextmanager
def _destination(kind: str, tmp_path: Path) -> Iterator[Path]:
    """An output folder of the given kind, holding a file ``figures.json`` that must survive."""
    if kind == "package":
        yield SHIPPED
    elif kind == "symlink into the package":
        link = tmp_path / "link"
        link.symlink_to(SHIPPED, target_is_directory=True)
        yield link
    elif kind == "read-only file system":
        with tmpfs(tmp_path / "ro", "size=1m") as mount:
            (mount / "figures.json").write_text('{"kept": true}\n')
            subprocess.run(["mount", "-o", "remount,ro", str(mount)], check=True)
            yield mount
    else:
        with tmpfs(tmp_path / "full", "size=64k") as mount:
            (mount / "figures.json").write_text('{"kept": true}\n')
            filler = mount / "filler"
            with contextlib.suppress(OSError), filler.open("wb") as f:
                while True:
                    f.write(b"\0" * 4096)
                    f.flush()
            yield mount


KINDS = ("package", "symlink into the package", "read-only file system", "full file system")


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("writer", list(WRITERS))
def test_every_writer_refuses_a_hostile_destination_and_changes_nothing(
    writer, kind, tmp_path, monkeypatch, capsys
):
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    argv = None
    package_before = _tree_hashes(PACKAGE_DIR)
    with _destination(kind, tmp_path) as dest:
        argv = WRITERS[writer](dest, tmp_path)
        dest_before = _tree_hashes(dest)
        capsys.readouterr()
        code = main(argv)
        err = capsys.readouterr().err
        dest_after = _tree_hashes(dest)
    assert code == EXIT_CODES["failure"], (argv, err)
    assert str(dest) in err and "Traceback" not in err, err
    assert dest_after == dest_before
    assert _tree_hashes(PACKAGE_DIR) == package_before
