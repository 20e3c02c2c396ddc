"""The planner on user PDDL: case, IPC-style costs, accepted requirements, trustworthy
"no plan", limits, and meaning errors named with file and line.

Each fixture's optimal cost is written down and, where Fast Downward is installed, also
taken from it (A* + LM-cut) and compared with every built-in planner's.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from osg_control.cli import main
from osg_control.commands.plan import NO_PLAN_EXIT, PDDL_ERROR_EXIT, UNKNOWN_EXIT
from osg_control.errors import PDDLError
from osg_control.planning import api
from osg_control.planning.api import plan_files
from osg_control.planning.classic import write_classic
from osg_control.planning.fast_downward import find_fast_downward
from osg_control.planning.grounding import ground
from osg_control.planning.heuristics import HMax
from osg_control.planning.lmcut import LMCut
from osg_control.planning.reader import read_pair
from osg_control.planning.task import SearchLimits

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "pddl"
needs_fd = pytest.mark.skipif(find_fast_downward() is None, reason="Fast Downward not installed")

OPTIMAL = {
    "case": 6,  # upper-case keywords and static predicates, type case differing across files
    "road": 2,  # the init's (ROAD a c) is the shortcut (road a c)
    "costs": 13,  # (increase (total-cost) (travel-slow ?f1 ?f2)) with values in :init
    "adl": 4,  # :types without :typing, object as a type, negation, equality
}


def _pair(name: str, problem: str | None = None) -> tuple[Path, Path]:
    return FIXTURES / f"{name}-domain.pddl", FIXTURES / f"{problem or name}-problem.pddl"


@pytest.mark.parametrize("planner", ["astar", "astar-hmax", "ucs", "auto"])
@pytest.mark.parametrize("name", sorted(OPTIMAL))
def test_fixture_is_solved_at_its_optimal_cost(name: str, planner: str) -> None:
    result = plan_files(*_pair(name), planner=planner)
    assert result.status == "solved"
    assert result.cost == OPTIMAL[name]


@pytest.mark.slow
@needs_fd
@pytest.mark.parametrize("name", sorted(OPTIMAL))
def test_fixture_cost_matches_fast_downward(name: str) -> None:
    fd = plan_files(*_pair(name), planner="fast-downward")
    assert fd.cost == plan_files(*_pair(name), planner="astar").cost == OPTIMAL[name]


def test_names_differing_in_case_are_one_name() -> None:
    result = plan_files(*_pair("road"))
    assert result.actions == ("drive a c", "drive c d")


def test_types_without_typing_warns() -> None:
    warnings: list[str] = []
    plan_files(*_pair("adl"), warn=warnings.append)
    assert len(warnings) == 1 and "adl-domain.pddl:5: :types without :typing" in warnings[0]


def test_negative_goal_is_kept() -> None:
    result = plan_files(*_pair("adl"))
    assert "(not (has k2))" in result.goal
    assert "take k2 hall" not in result.actions


@pytest.mark.parametrize("planner", ["astar", "ucs", "auto"])
def test_unsolvable_task_exits_3(planner: str, capsys: pytest.CaptureFixture[str]) -> None:
    files = [str(p) for p in _pair("adl", "unsolvable")]
    assert main(["plan", *files, "--planner", planner]) == NO_PLAN_EXIT
    assert "no plan for (in vault)" in capsys.readouterr().out


@needs_fd
def test_fast_downward_proves_unsolvable_too() -> None:
    assert plan_files(*_pair("adl", "unsolvable"), planner="fast-downward").status == "unsolvable"


def test_limit_bound_search_is_unknown_not_no_plan(capsys: pytest.CaptureFixture[str]) -> None:
    files = [str(p) for p in _pair("costs")]
    code = main(["plan", *files, "--planner", "ucs", "--max-states", "3"])
    assert code == UNKNOWN_EXIT != NO_PLAN_EXIT
    assert "stopped at the state limit 3" in capsys.readouterr().out
    result = plan_files(*_pair("costs"), "astar", SearchLimits(time_s=0.0))
    assert result.status == "unknown" and result.limit == "time limit 0 s"


DOMAIN = """(define (domain d)
  (:requirements :strips :typing)
  (:types block)
  (:constants table - block)
  (:predicates (on ?x ?y - block) (clear ?x - block))
  (:action move
    :parameters (?x ?y - block)
    :precondition (and (clear ?x) (on ?x ?y))
    :effect (and (not (on ?x ?y)) (on ?x table))))
"""
PROBLEM = """(define (problem p)
  (:domain d)
  (:objects a b - block)
  (:init (on a b) (clear a))
  (:goal (on a table)))
"""


@pytest.mark.parametrize(
    ("file", "old", "new", "message"),
    [
        (
            "domain",
            "(clear ?x) (on",
            "(Clear-Top ?x) (on",
            "domain.pddl:8: undeclared predicate 'Clear-Top'",
        ),
        ("domain", "(on ?x ?y))\n", "(on ?x))\n", "domain.pddl:8: predicate 'on' takes 2 argument"),
        ("domain", "(on ?x TABLE)", "(on ?x floor)", "domain.pddl:9: undeclared object 'floor'"),
        ("domain", "(on ?x TABLE)", "(on ?z table)", "domain.pddl:9: undeclared variable '?z'"),
        ("domain", "(?x ?y - block)", "(?x ?y - Brick)", "domain.pddl:7: undeclared type 'Brick'"),
        (
            "domain",
            "(:action move",
            "(:action MOVE :parameters () :effect ())\n  (:action move",
            "domain.pddl:7: action 'move' is defined twice",
        ),
        ("problem", "(clear a)", "(clear c)", "problem.pddl:4: undeclared object 'c'"),
        ("problem", "(clear a)", "(Clean a)", "problem.pddl:4: undeclared predicate 'Clean'"),
        ("problem", "(:domain d)", "(:domain e)", "problem.pddl:2: problem is for domain 'e'"),
        ("problem", "a b - block", "a b - stone", "problem.pddl:3: undeclared type 'stone'"),
        (
            "domain",
            "(and (clear",
            "(and (forall (?z - block) (clear ?z)) (clear",
            "domain.pddl:8: 'forall' needs :universal-preconditions",
        ),
    ],
)
def test_meaning_errors_name_file_line_and_name(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    file: str,
    old: str,
    new: str,
    message: str,
) -> None:
    texts = {"domain": DOMAIN.replace("table))))", "TABLE))))"), "problem": PROBLEM}
    assert old in texts[file]
    texts[file] = texts[file].replace(old, new, 1)
    paths = []
    for kind, text in texts.items():
        path = tmp_path / f"{kind}.pddl"
        path.write_text(text)
        paths.append(path)
    with pytest.raises(PDDLError, match=re.escape(message)):
        plan_files(*paths)
    assert main(["plan", *map(str, paths)]) == PDDL_ERROR_EXIT
    assert message.split(": ", 1)[1] in capsys.readouterr().err


def test_unbroken_inline_pair_plans(tmp_path: Path) -> None:
    (tmp_path / "domain.pddl").write_text(DOMAIN)
    (tmp_path / "problem.pddl").write_text(PROBLEM)
    assert plan_files(tmp_path / "domain.pddl", tmp_path / "problem.pddl").actions == ("move a b",)


@pytest.mark.slow
@pytest.mark.parametrize(("name", "size"), [("gripper", 3), ("blocks", 5), ("logistics", 3)])
def test_lmcut_is_admissible_and_dominates_hmax(name: str, size: int, tmp_path: Path) -> None:
    pair = read_pair(*write_classic(name, size, tmp_path))
    task = ground(pair.domain, pair.problem)
    result = plan_files(*write_classic(name, size, tmp_path), planner="ucs")
    assert result.cost is not None
    lmcut, hmax = LMCut(task), HMax(task)
    state, cost_to_go = task.init, result.cost
    for step in result.steps or ():
        assert hmax(state) <= lmcut(state) <= cost_to_go
        state = task.operator(step.action).apply(state)
        cost_to_go -= step.cost
    assert lmcut(state) == 0


@needs_fd
def test_auto_hands_a_task_past_its_budget_to_fast_downward(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(api, "AUTO_BUDGET", SearchLimits(max_states=2))
    result = plan_files(*_pair("costs"), planner="auto")
    assert result.planner == "fast-downward" and result.cost == OPTIMAL["costs"]
