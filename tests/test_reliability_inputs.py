"""Reliability, round 3: tampered or malformed figures never pass ``reproduce --compare``;
bad action costs are malformed PDDL; bad plan limits are usage errors; a models folder that
lacks a skill, or holds a checkpoint with a foreign ``action_scale`` or another skill's
weights, is a named ``CheckpointError``. Each case: the exit code, a message fragment, and
no file changed."""

from __future__ import annotations

import copy
import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from osg_control import cli
from osg_control.domain.registry import get_domain
from osg_control.errors import EXIT_CODES, CheckpointError, PDDLError
from osg_control.evaluation.check import compare
from osg_control.execution import defaults
from osg_control.learning.checkpoints import NORMALISATION_KEYS, values_sha256

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "osg_control/kitchen/defaults"
FIXTURES = ROOT / "tests/fixtures/pddl"
KITCHEN = get_domain("kitchen")


def _snapshot(*folders: Path) -> dict[str, bytes]:
    """Every file under ``folders`` with its bytes (to show that nothing changed)."""
    return {
        str(path): path.read_bytes()
        for folder in folders
        for path in sorted(folder.rglob("*"))
        if path.is_file()
    }


def _shipped_figures() -> dict[str, Any]:
    return json.loads((SHIPPED / "figures.json").read_text())


def _set(path: tuple[Any, ...], value: Any) -> Callable[[dict[str, Any]], Any]:
    """A tampering: the entry at ``path`` set to ``value``."""

    def tamper(figures: dict[str, Any]) -> Any:
        *parents, last = path
        target = figures
        for key in parents:
            target = target[key]
        target[last] = value
        return figures

    return tamper


def _drop(path: tuple[Any, ...]) -> Callable[[dict[str, Any]], Any]:
    """A tampering: the entry at ``path`` removed."""

    def tamper(figures: dict[str, Any]) -> Any:
        *parents, last = path
        target = figures
        for key in parents:
            target = target[key]
        del target[last]
        return figures

    return tamper


NAN = float("nan")
TAMPERED = [
    # NaN and Infinity are not JSON: the reader refuses them (json_files)
    ("nan rate", _set(("table_i", "rows", 0, "rates", 0), NAN), "NaN is not a JSON number"),
    ("inf rate", _set(("table_ii", "accuracy"), float("inf")), "Infinity is not a JSON number"),
    ("rate above 1", _set(("table_iii", "rows", 0, "success"), 1.5), "Table III home: rate must"),
    ("negative rate", _set(("tables_iv_v", "rates", 0, 0, 0), -0.1), "pick-up home: rate must"),
    ("no episodes", _set(("table_i", "episodes"), 0), "Table I: 'episodes' must be a positive"),
    ("negative episodes", _set(("table_iii", "episodes"), -5), "Table III: 'episodes' must be"),
    ("no states", _set(("table_ii", "num_states"), 0), "Table II: 'num_states' must be a positive"),
    # the eight malformed shapes
    ("top level a list", lambda figures: [figures], "not a JSON object"),
    ("a table missing", _drop(("table_iii",)), "lacks 8 of the 179 cells"),
    ("a table of the wrong type", _set(("table_i",), [1]), "Table I: 'table_i' must be a JSON"),
    ("rows not a list", _set(("table_iii", "rows"), {}), "Table III 'rows': must be a list"),
    ("a row missing its rate", _drop(("table_iii", "rows", 0, "success")), "'success' is missing"),
    ("a rate that is a string", _set(("table_i", "rows", 0, "rates", 1), "1.0"), 'got "1.0"'),
    ("episodes a string", _set(("tables_iv_v", "episodes"), "100"), "'episodes' must be a"),
    ("episodes a float", _set(("table_i", "episodes"), 200.0), "got 200.0"),
    ("extra nesting", _set(("tables_iv_v", "rates", 0, 0, 0), [0.9]), "rate must be a finite"),
    # shapes that would drop or duplicate cells
    ("a row missing", _drop(("table_i", "rows", 3)), "lacks 3 of the 179 cells"),
    ("a task short", _drop(("tables_iv_v", "rates", 1, 2)), "replans=2: must be a list of 7"),
    ("a noise level short", _drop(("table_i", "rows", 0, "rates", 2)), "must be a list of 3"),
    (
        "a row twice",
        lambda f: f["table_iii"]["rows"].append(f["table_iii"]["rows"][1]) or f,
        "twice",
    ),
    ("no table at all", lambda figures: {"run": figures["run"]}, "share no table cell"),
]


@pytest.mark.parametrize(("case", "tamper", "fragment"), TAMPERED, ids=[t[0] for t in TAMPERED])
def test_compare_refuses_tampered_or_malformed_figures(
    case: str,
    tamper: Callable[[dict[str, Any]], Any],
    fragment: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    report = tmp_path / "figures.json"
    report.write_text(json.dumps(tamper(_shipped_figures())))
    before = _snapshot(tmp_path, SHIPPED)
    assert cli.main(["reproduce", "--compare", str(tmp_path)]) == EXIT_CODES["failure"], case
    captured = capsys.readouterr()
    assert "cells compared" not in captured.out  # never a verdict, let alone a pass
    assert captured.err.startswith(f"osg: error: {report}: ") and fragment in captured.err
    assert "internal error" not in captured.err and "Traceback" not in captured.err
    assert _snapshot(tmp_path, SHIPPED) == before


@pytest.mark.parametrize(
    ("tamper", "fragment"),
    [
        (_set(("table_i", "rows", 0, "rates", 0), NAN), "NaN is not a JSON number"),
        (_set(("table_iii", "episodes"), 0), "Table III: 'episodes' must be a positive"),
        (_set(("tables_iv_v", "rates"), "x"), "Tables IV/V 'rates': must be a list of 2"),
    ],
)
def test_compare_validates_the_shipped_figures_too(
    tamper: Callable[[dict[str, Any]], Any],
    fragment: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    shipped = tmp_path / "shipped"
    shipped.mkdir()
    (shipped / "figures.json").write_text(json.dumps(tamper(_shipped_figures())))
    (tmp_path / "figures.json").write_text(json.dumps(_shipped_figures()))
    monkeypatch.setattr(defaults, "defaults_root", lambda domain, directory=None: shipped)
    assert cli.main(["reproduce", "--compare", str(tmp_path)]) == EXIT_CODES["failure"]
    err = capsys.readouterr().err
    assert err.startswith(f"osg: error: {shipped / 'figures.json'}: ") and fragment in err


def test_untampered_figures_still_pass_and_extra_cells_are_not_compared() -> None:
    figures = _shipped_figures()
    assert (compare(figures, figures).compared, compare(figures, figures).mismatches) == (179, [])
    more = copy.deepcopy(figures)
    more["table_i"]["rows"].append({"skill": "new-skill", "rates": [1.0, 1.0, 1.0]})
    assert (compare(figures, more).compared, compare(figures, more).mismatches) == (179, [])


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["--time-limit", "-1"], "--time-limit"),
        (["--time-limit", "0"], "--time-limit"),
        (["--time-limit", "nan"], "--time-limit"),
        (["--time-limit", "inf"], "--time-limit"),
        (["--max-states", "0"], "--max-states"),
        (["--max-states", "-5"], "--max-states"),
    ],
)
def test_plan_limits_out_of_range_are_usage_errors(
    argv: list[str],
    option: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    no_physics: None,
) -> None:
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path))
    assert cli.main(["plan", "--goal", "door-open", *argv]) == EXIT_CODES["usage"]
    captured = capsys.readouterr()
    assert captured.err.startswith(f"osg: error: {option} must ") and "got" in captured.err
    assert captured.out == ""  # nothing planned
    assert not any(tmp_path.iterdir())


COSTS = {
    "domain": ("(increase (total-cost) 0)", "(increase (total-cost) {})", 22),
    "problem": ("(= (travel-slow n0 n1) 6)", "(= (travel-slow n0 n1) {})", 6),
}
"""Where the costs fixture gets a bad cost: the text, its replacement, its line (``board``'s
constant cost in the domain, the value of ``(travel-slow n0 n1)`` in the problem)."""


@pytest.mark.parametrize("value", ["1e999", "nan", "inf", "-nan", "1e3", "-3", "2.5", "abc"])
@pytest.mark.parametrize("where", ["domain", "problem"])
def test_action_costs_that_are_not_non_negative_integers_are_malformed_pddl(
    value: str, where: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    files = {kind: FIXTURES / f"costs-{kind}.pddl" for kind in ("domain", "problem")}
    old, new, line = COSTS[where]
    text = files[where].read_text()
    assert old in text
    files[where] = tmp_path / f"{where}.pddl"
    files[where].write_text(text.replace(old, new.format(value), 1))
    before = _snapshot(tmp_path)
    code = cli.main(["plan", str(files["domain"]), str(files["problem"])])
    err = capsys.readouterr().err
    assert code == EXIT_CODES["pddl input"], err
    assert err.startswith(f"osg: error: {files[where]}:{line}: ")
    expected = f"expected a cost, got '{value}'" if value == "abc" else f"cost {value} is not a"
    assert expected in err and "internal error" not in err
    assert _snapshot(tmp_path) == before


@pytest.mark.parametrize("value", [float("inf"), float("nan"), -1.0, 2.5])
def test_grounding_refuses_a_non_integer_cost_built_in_code(value: float) -> None:
    from pddl.core import Problem
    from pddl.logic.functions import EqualTo, NumericValue

    from osg_control.planning.grounding import ground
    from osg_control.planning.reader import read_pair

    pair = read_pair(FIXTURES / "costs-domain.pddl", FIXTURES / "costs-problem.pddl")
    problem = pair.problem
    init = [
        EqualTo(item.operands[0], NumericValue(value))
        if isinstance(item, EqualTo) and item.operands[0].name == "travel-slow"
        else item
        for item in problem.init
    ]
    edited = Problem(
        problem.name,
        domain=pair.domain,
        objects=problem.objects,
        init=init,
        goal=problem.goal,
        metric=problem.metric,
    )
    with pytest.raises(PDDLError, match=f"has value {value}; an action cost must be a non-neg"):
        ground(pair.domain, edited)


@pytest.mark.parametrize(
    ("key", "value", "fragment"),
    [
        ("success_rate", "0.9", "success rate 0.9 not in [0, 1]"),
        ("success_rate", True, "success rate True not in [0, 1]"),
        ("success_rate", NAN, "NaN is not a JSON number"),  # refused by the reader
        ("step_cost", 1e999, "Infinity is not a JSON number"),
        ("step_cost", "x", "ValueError"),
    ],
)
def test_plan_refuses_a_graph_with_a_malformed_rate_or_cost(
    key: str, value: Any, fragment: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from osg_control.planning.graph import graph_from_specs

    graph = graph_from_specs(KITCHEN).to_dict()
    graph["edges"][0][key] = value
    path = tmp_path / "graph.json"
    path.write_text(json.dumps(graph))
    before = _snapshot(tmp_path)
    assert cli.main(["plan", "--goal", "door-open", "--graph", str(path)]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"osg: error: {path}: ") and fragment in err
    assert "internal error" not in err and _snapshot(tmp_path) == before


def _models_folder(root: Path, skip: str | None = None) -> Path:
    """A defaults folder linking to the shipped one's files (``skip``'s checkpoint left out)."""
    folder = root / "models"
    (folder / "skills").mkdir(parents=True)
    for name in ("classifier", "manifest.json"):
        (folder / name).symlink_to(SHIPPED / name)
    for path in (SHIPPED / "skills").iterdir():
        if path.stem != skip:
            (folder / "skills" / path.name).symlink_to(path)
    return folder


MISSING_SKILL_COMMANDS = [
    ["run", "--goal", "door-open", "--models", "{models}"],
    ["eval-skills", "--episodes", "1", "--models", "{models}/skills"],
    ["eval-skills", "--skill", "grab-handle", "--episodes", "1", "--models", "{models}/skills"],
    ["evaluate", "tasks", "--episodes", "1", "--models", "{models}"],
    ["classifier", "reach", "--episodes", "1", "--models", "{models}"],
]


@pytest.mark.parametrize("argv", MISSING_SKILL_COMMANDS, ids=lambda argv: " ".join(argv[:2]))
def test_a_skill_missing_from_the_models_folder_is_named_before_any_work(
    argv: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    no_physics: None,
) -> None:
    cache = tmp_path / "cache"
    monkeypatch.setenv("OSG_CACHE_DIR", str(cache))
    models = _models_folder(tmp_path, skip="grab-handle")
    before = _snapshot(tmp_path)
    code = cli.main([arg.format(models=models) for arg in argv])
    err = capsys.readouterr().err
    assert code == EXIT_CODES["failure"], err
    assert err.startswith(
        f"osg: error: {models / 'skills'}: no checkpoint of skill(s) grab-handle "
    )
    assert _snapshot(tmp_path) == before and not cache.exists()


@pytest.mark.slow
def test_a_models_folder_holding_the_named_skills_is_enough_for_eval_skills(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path / "cache"))
    models = _models_folder(tmp_path, skip="grab-handle") / "skills"
    argv = ["eval-skills", "--skill", "move-home-to-door", "--episodes", "1", "--noise", "0"]
    assert cli.main([*argv, "--workers", "1", "--models", str(models)]) == 0
    assert "move-home-to-door" in capsys.readouterr().out


def _edit_sidecar(name: str, edit: Callable[[dict[str, Any]], None]) -> Callable[[Path], None]:
    def apply(skills: Path) -> None:
        path = skills / f"{name}.json"
        sidecar = json.loads(path.read_text())
        edit(sidecar)
        # resealed: these checks are about values that are consistent but wrong
        # (tests/test_reliability_sidecars.py covers edits that break the checksum)
        sidecar["normalisation_sha256"] = values_sha256(
            {key: sidecar[key] for key in NORMALISATION_KEYS}
        )
        path.unlink()  # a link to the shipped file: replace it, never write through it
        path.write_text(json.dumps(sidecar))

    return apply


def _weights_of(source: str, target: str) -> Callable[[Path], None]:
    """``source``'s weights and sidecar under ``target``'s name, the sidecar's spec edited
    to ``target``'s (a copy that passes the sidecar's own skill-name check)."""

    def apply(skills: Path) -> None:
        sidecar = json.loads((SHIPPED / "skills" / f"{source}.json").read_text())
        sidecar["skill_spec"] = json.loads((SHIPPED / "skills" / f"{target}.json").read_text())[
            "skill_spec"
        ]
        for suffix in (".json", ".safetensors"):
            (skills / f"{target}{suffix}").unlink()
        (skills / f"{target}.json").write_text(json.dumps(sidecar))
        shutil.copyfile(
            SHIPPED / "skills" / f"{source}.safetensors", skills / f"{target}.safetensors"
        )

    return apply


def _scale(values: list[float]) -> Callable[[dict[str, Any]], None]:
    return lambda sidecar: sidecar.__setitem__("action_scale", values)


FRANKA_SCALE = [0.04, 0.04, 0.04, 0.2, 0.2, 0.2, 1.0]
KITCHEN_SCALE = [0.02, 0.02, 0.02, 0.1, 0.1, 0.1, 1.0]


@pytest.mark.parametrize(
    ("tamper", "file", "fragment"),
    [
        (
            _edit_sidecar("grab-cube", _scale(FRANKA_SCALE)),
            "grab-cube.json",
            "action_scale [0.04, 0.04, 0.04, 0.2, 0.2, 0.2, 1.0] is not the domain's action bounds "
            "[0.02, 0.02, 0.02, 0.1, 0.1, 0.1, 1.0]",
        ),
        (
            _edit_sidecar("grab-cube", _scale([0.02, 0.02, 0.02, 0.1, 0.1, 0.1, 1.01])),
            "grab-cube.json",
            "is not the domain's action bounds",
        ),
        (_edit_sidecar("grab-cube", _scale(KITCHEN_SCALE[:6])), "grab-cube.json", "7 positive"),
        (
            _edit_sidecar("grab-cube", _scale([*KITCHEN_SCALE[:6], float("nan")])),
            "grab-cube.json",
            "NaN is not a JSON number",  # refused by the reader (json_files)
        ),
        (
            _edit_sidecar(
                "grab-cube", lambda s: s["skill_spec"].__setitem__("name", "pick-up-cube")
            ),
            "grab-cube.json",
            "checkpoint is for skill 'pick-up-cube', but skill 'grab-cube' was requested",
        ),
        (
            _weights_of("grab-cube", "grab-handle"),
            "grab-handle.safetensors",
            "saved for skill 'grab-cube' (safetensors metadata), but skill 'grab-handle' was",
        ),
    ],
    ids=[
        "another domain's scale",
        "scale 1 % off",
        "scale of 6",
        "nan in the scale",
        "sidecar of another skill",
        "weights of another skill",
    ],
)
def test_implausible_action_scale_or_another_skills_weights_are_refused(
    tamper: Callable[[Path], None],
    file: str,
    fragment: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path / "cache"))
    models = _models_folder(tmp_path)
    tamper(models / "skills")
    before = _snapshot(tmp_path, SHIPPED / "skills")
    with pytest.raises(CheckpointError, match=r"^" + str(models / "skills" / file)) as err:
        defaults.load_skill_policies(KITCHEN, models / "skills")
    assert fragment in str(err.value)
    assert cli.main(["run", "--goal", "door-open", "--models", str(models)]) == 1
    assert f"osg: error: {models / 'skills' / file}: " in capsys.readouterr().err
    assert _snapshot(tmp_path, SHIPPED / "skills") == before
