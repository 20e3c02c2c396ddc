"""Reliability, round 4: every number has a documented range, checked up front.

The CLI property: the parser is walked for every numeric option of every verb (so a new
option without a bound fails here), and each is fed its extremes (0, negative, NaN, inf,
1e308, 1e29, a 30-digit and a 5,000-digit integer, 100,000); every value outside the
option's documented range (``BOUNDS``, as docs/reliability.md lists them) exits 2 naming
the option, with nothing written. The API: the same numbers handed to the calls and files
that take them are named errors."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from osg_control import cli
from osg_control.control.estimator import TcpFilter
from osg_control.domain.registry import get_domain
from osg_control.errors import EXIT_CODES, CheckpointError, DatasetError, UsageError
from osg_control.evaluation.check import cells, wilson_interval
from osg_control.execution.bundle import manifest_motion_model
from osg_control.execution.executor import load_executor
from osg_control.perception.spec import PerceptionSpec, perception_spec
from osg_control.planning.task import SearchLimits

BOUNDS: dict[str, tuple[float, float, bool, bool]] = {
    "episodes": (1, 1e9, False, False),
    "steps": (1, 1e9, False, False),
    "check_every": (1, 1e9, False, False),
    "check_episodes": (1, 1e9, False, False),
    "patience": (1, 1e9, False, False),
    "epochs": (1, 1e6, False, False),
    "batch_size": (1, 2**20, False, False),
    "threads": (1, 1024, False, False),
    "workers": (1, 1024, False, False),
    "seed": (0, 2**32 - 1, False, False),
    "replans": (0, 1000, False, False),
    "max_replans": (0, 1000, False, False),
    "max_states": (1, 2**31 - 1, False, False),
    "noise": (0, 1, False, False),
    "object_noise": (0, 1, False, False),
    "obs_noise": (0, 1, False, False),
    "time_limit": (0, 1e6, True, False),
    "filter": (0, 1, True, False),
    "validation_fraction": (0, 1, False, True),
}
"""Each numeric option's documented range: (low, high, low open, high open)."""
EXTREMES = ["0", "-1", "nan", "inf", "-inf", "1e308", "1e29", "9" * 30, "9" * 5000, "100000"]
REQUIRED = {("run",): ["--goal", "door-open"], ("train",): ["--skill", "grab-cube"]}
"""The other arguments a verb needs to parse."""
DOMAIN = {("evaluate", "benchmark"): "franka-kitchen"}


def _numeric_options() -> Iterator[tuple[tuple[str, ...], str, str]]:
    """(verb path, option, destination) of every option whose type parses to a number."""

    def walk(parser: argparse.ArgumentParser, path: tuple[str, ...]) -> Iterator[Any]:
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    yield from walk(sub, (*path, name))
            elif action.option_strings and action.type is not None:
                try:
                    parsed = action.type("1")  # type: ignore[operator]
                except Exception:  # noqa: BLE001 - a type that takes no "1" is not numeric
                    continue
                if isinstance(parsed, int | float) and not isinstance(parsed, bool):
                    yield path, action.option_strings[0], action.dest

    yield from walk(cli.build_parser(), ())


OPTIONS = sorted(set(_numeric_options()))


def _in_range(dest: str, text: str) -> bool:
    low, high, low_open, high_open = BOUNDS[dest]
    try:
        value = float(text)
    except (ValueError, OverflowError):
        return False
    if not math.isfinite(value) or (value <= low if low_open else value < low):
        return False
    return value < high if high_open else value <= high


def test_every_numeric_option_has_a_documented_range() -> None:
    assert len(OPTIONS) > 50
    missing = sorted({dest for _path, _option, dest in OPTIONS} - set(BOUNDS))
    assert not missing, f"numeric options without a documented range: {missing}"
    reliability = (Path(__file__).resolve().parents[1] / "docs/reliability.md").read_text()
    for dest in BOUNDS:
        assert f"`--{dest.replace('_', '-')}`" in reliability, dest


CASES = [
    (path, option, dest, value)
    for path, option, dest in OPTIONS
    for value in EXTREMES
    if not _in_range(dest, value)
]


@pytest.mark.parametrize(
    ("path", "option", "dest", "value"),
    CASES,
    ids=[f"{' '.join(c[0])} {c[1]} {c[3][:8]}" for c in CASES],
)
def test_every_numeric_option_refuses_its_extremes_with_exit_2(
    path: tuple[str, ...],
    option: str,
    dest: str,
    value: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path / "cache"))
    argv = ["--domain", DOMAIN.get(path, "kitchen"), *path, f"{option}={value}"]
    argv += REQUIRED.get(path, [])  # the --option=value form: "-inf" is a value, not a flag
    try:
        code = cli.main(argv)
    except SystemExit as stop:  # argparse's own refusal (not a number of the option's type)
        code = stop.code
    assert code == EXIT_CODES["usage"], argv
    err = capsys.readouterr().err
    assert option in err and "Traceback" not in err and "internal error" not in err
    assert not any(tmp_path.iterdir())  # nothing written


HUGE = 10**400
API: list[tuple[str, Callable[[], Any], type[Exception], str]] = [
    ("perception_spec noise 1e300", lambda: perception_spec("paper", 1e300), UsageError, "[0, 1]"),
    ("perception_spec noise inf", lambda: perception_spec("robot", 0.0, math.inf), UsageError, ""),
    ("PerceptionSpec object noise", lambda: PerceptionSpec(object_noise=2.0), UsageError, "[0, 1]"),
    (
        "PerceptionSpec angle noise",
        lambda: PerceptionSpec(object_angle_noise=1e300),
        UsageError,
        "",
    ),
    ("time limit 1e308", lambda: SearchLimits(time_s=1e308), ValueError, "time limit"),
    ("time limit nan", lambda: SearchLimits(time_s=math.nan), ValueError, "time limit"),
    ("max states huge", lambda: SearchLimits(max_states=HUGE), ValueError, "max_states"),
    ("max states True", lambda: SearchLimits(max_states=True), ValueError, "max_states"),
    ("motion model 1e300", lambda: TcpFilter(0.2, (1e300, 1e300)), ValueError, "motion model"),
    ("filter gain nan", lambda: TcpFilter(math.nan), ValueError, "filter gain"),
    (
        "manifest motion model",
        lambda: manifest_motion_model({"motion_model": [1e300, 1e300]}, Path("m.json")),
        CheckpointError,
        "m.json: 'motion_model'",
    ),
    ("wilson huge trials", lambda: wilson_interval(0.5, HUGE), ValueError, "at most"),
    (
        "401-digit trial count",
        lambda: list(
            cells({"table_iii": {"episodes": 10**400, "rows": [{"start": "r", "success": 0.5}]}})
        ),
        DatasetError,
        "'episodes' must be a positive integer <= 1,000,000,000",
    ),
]


@pytest.mark.parametrize(("case", "call", "error", "fragment"), API, ids=[a[0] for a in API])
def test_api_numbers_out_of_range_are_named_errors(
    case: str, call: Callable[[], Any], error: type[Exception], fragment: str
) -> None:
    with pytest.raises(error) as raised:
        call()
    assert fragment in str(raised.value), case


@pytest.mark.parametrize("value", [-1, 1001, True, 2.5, "2"])
def test_an_executor_refuses_a_replanning_budget_out_of_range(value: Any) -> None:
    with pytest.raises(ValueError, match=r"max_replans must be a whole number in \[0, 1000\]"):
        load_executor(get_domain("kitchen"), max_replans=value)
