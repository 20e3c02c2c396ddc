"""The lazily built ``osg`` parser lists and parses every verb exactly as the full one does."""

from __future__ import annotations

import argparse

import pytest

from osg_control.cli import VERBS, _modules_for, build_parser
from osg_control.commands import COMMAND_MODULES


def _verb_parsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def test_verb_table_matches_the_modules() -> None:
    full = build_parser()
    assert build_parser([]).format_help() == full.format_help()
    assert [verb for verb, _, _ in VERBS] == list(_verb_parsers(full))
    assert {module for _, module, _ in VERBS} == set(COMMAND_MODULES)


@pytest.mark.parametrize("verb", [verb for verb, _, _ in VERBS])
def test_each_verb_parses_as_in_the_full_parser(verb: str) -> None:
    lazy = _verb_parsers(build_parser(_modules_for(["--version", verb, "--help"])))[verb]
    assert lazy.format_help() == _verb_parsers(build_parser())[verb].format_help()


def test_domain_after_the_verb_means_the_same() -> None:
    from osg_control.cli import hoist_global_options

    assert hoist_global_options(["reproduce", "--domain", "mini", "--quick"]) == [
        "--domain",
        "mini",
        "reproduce",
        "--quick",
    ]
    assert hoist_global_options(["plan", "--domain=mini"]) == ["--domain=mini", "plan"]
    assert hoist_global_options(["--domain", "mini", "plan"]) == ["--domain", "mini", "plan"]
