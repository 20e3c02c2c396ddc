"""Reliability, round 4: one JSON reader (``json_files``) for everything read from users.
Every reader, through the CLI where a verb reads the file, is fed every hostile JSON:
nesting past Python's parser, an integer over its 4,300 digits, NaN, bytes that are not
UTF-8, a truncated text, a file over the size bound and ``/dev/zero``. Each is the
package's error naming the file (exit 1 on the CLI), never an internal error or a hang;
``--env-kwargs`` is a command-line value, so exit 2."""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from osg_control import cli, json_files
from osg_control.classifier.model import SIDECAR_FILE, StateClassifier
from osg_control.data.minari_import import _read_metadata
from osg_control.errors import EXIT_CODES, OSGError
from osg_control.execution.bundle import read_manifest
from osg_control.json_files import JSONFormatError, parse_json
from osg_control.learning.checkpoints import load_checkpoint
from osg_control.planning.graph import load_graph

LIMIT = 1 << 20
"""The size bound for these tests (the real one, 64 MiB, is too slow to exceed here)."""

CONTENTS: dict[str, tuple[bytes | None, str]] = {
    "deep nesting": (b"[" * 200_000, "nested too deeply"),
    "deep objects": (b'{"a":' * 200_000, "nested too deeply"),
    "huge integer": (b'{"a": ' + b"9" * 5000 + b"}", "a number too large to read"),
    "NaN": (b'{"a": NaN}', "NaN is not a JSON number"),
    "-Infinity": (b'{"a": -Infinity}', "-Infinity is not a JSON number"),
    "not UTF-8": (b'\xff\xfe{"a": 1}', "not UTF-8 text"),
    "truncated": (b'{"a": [1, 2', "not JSON"),
    "over the bound": (b'{"a": "' + b"x" * (2 * LIMIT) + b'"}', f"larger than {LIMIT} bytes"),
    "/dev/zero": (None, f"larger than {LIMIT} bytes"),
}


def _plant(path: Path, content: bytes | None) -> None:
    """``content`` at ``path``; None: a link to /dev/zero (endless bytes)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if content is None:
        path.symlink_to("/dev/zero")
    else:
        path.write_bytes(content)


def _cli(argv: Callable[[Path], list[str]], name: str) -> Callable[[Path], int]:
    def run(tmp: Path) -> int:
        return cli.main(argv(tmp))

    run.__name__ = name
    return run


READERS: dict[str, tuple[str, Callable[[Path], object]]] = {
    "reproduce --compare": (
        "figures.json",
        _cli(lambda t: ["reproduce", "--compare", str(t / "figures.json")], "compare"),
    ),
    "plan --graph": (
        "graph.json",
        _cli(lambda t: ["plan", "--goal", "door-open", "--graph", str(t / "graph.json")], "plan"),
    ),
    "graph --rates": (
        "rates.json",
        _cli(lambda t: ["graph", "--rates", str(t / "rates.json")], "graph"),
    ),
    "manifest": ("models/manifest.json", lambda t: read_manifest(t / "models")),
    "skill graph": ("graph.json", lambda t: load_graph(t / "graph.json")),
    "checkpoint sidecar": (
        "models/grab-cube.json",
        lambda t: load_checkpoint(t / "models", "grab-cube"),
    ),
    "classifier sidecar": (f"clf/{SIDECAR_FILE}", lambda t: StateClassifier.load(t / "clf")),
    "minari metadata": ("m/metadata.json", lambda t: _read_metadata(t / "m")),
}


@pytest.mark.parametrize("content", list(CONTENTS), ids=list(CONTENTS))
@pytest.mark.parametrize("reader", list(READERS), ids=list(READERS))
def test_every_json_reader_names_every_failure(
    reader: str,
    content: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setattr(json_files, "MAX_JSON_BYTES", LIMIT)
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path / "cache"))
    where, read = READERS[reader]
    data, reason = CONTENTS[content]
    path = tmp_path / where
    _plant(path, data)
    for sibling in ("classifier.safetensors", "grab-cube.safetensors"):
        (path.parent / sibling).write_bytes(b"")  # the reader gets as far as the JSON
    started = time.perf_counter()
    if read.__name__ in ("compare", "plan", "graph"):
        assert read(tmp_path) == EXIT_CODES["failure"]
        err = capsys.readouterr().err
        assert err.startswith(f"osg: error: {path}: ") and "internal error" not in err
        message = err
    else:
        with pytest.raises(OSGError) as raised:
            read(tmp_path)
        message = str(raised.value)
    if (reader, content) == ("classifier sidecar", "/dev/zero"):
        reason = "is not a regular file"  # refused before it is read
    assert str(path) in message and reason in message
    assert time.perf_counter() - started < 10.0


@pytest.mark.parametrize(
    "value",
    ["[" * 100_000, '{"a":' * 100_000, '{"a": ' + "9" * 5000 + "}", '{"a": NaN}', "{", "[1]"],
    ids=["deep list", "deep object", "huge integer", "NaN", "truncated", "a list"],
)
def test_env_kwargs_that_are_not_a_readable_json_object_exit_2(
    value: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path))
    argv = ["--domain", "franka-kitchen", "evaluate", "benchmark", "--env-kwargs", value]
    try:
        code = cli.main(argv)
    except SystemExit as stop:  # argparse's own refusal of an option's value
        code = stop.code
    assert code == EXIT_CODES["usage"]
    err = capsys.readouterr().err
    assert "--env-kwargs" in err and "Traceback" not in err and "internal error" not in err
    assert not any(tmp_path.iterdir())


def test_the_reader_accepts_ordinary_json_and_bounds_memory(tmp_path: Path) -> None:
    assert parse_json(b'{"a": [1, 2.5, "x", null, true]}') == {"a": [1, 2.5, "x", None, True]}
    nested = parse_json("[" * 50 + "]" * 50)  # ordinary nesting reads
    for _ in range(49):
        (nested,) = nested
    assert nested == []
    link = tmp_path / "zero.json"
    os.symlink("/dev/zero", link)
    started = time.perf_counter()
    with pytest.raises(JSONFormatError, match="larger than"):
        json_files.load_json(link, limit=1 << 20)
    assert time.perf_counter() - started < 5.0
    (tmp_path / "ok.json").write_text(json.dumps({"k": 1}))
    assert json_files.read_json_object(tmp_path / "ok.json", "x", OSGError) == {"k": 1}


@pytest.mark.parametrize(
    ("value", "where"),
    [({"a": [1.0, math.nan]}, "['a'][1]"), ([{"b": math.inf}], "[0]['b']"), (-math.inf, "top")],
)
def test_json_output_is_always_json(value: object, where: str) -> None:
    """``--json`` printed a bare ``NaN`` (not JSON) when a result held one."""
    assert json.loads(json_files.dump_json({"x": [1.5, None, "s"]})) == {"x": [1.5, None, "s"]}
    with pytest.raises(OSGError, match="non-finite number at") as raised:
        json_files.dump_json(value)
    assert where in str(raised.value)
