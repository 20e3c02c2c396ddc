"""The lifted domain osg-libero over LIBERO's task files (the ``libero`` extra; skipped
without it): every task's goal of the 16 suites planned by the built-in planner, Fast
Downward's cost the same; the domain written beside the problems and read back by the
core's PDDL reader; drawers, doors and knobs the files leave unsaid; goals no operator
achieves named."""

from __future__ import annotations

import json
import os
import statistics
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from osg_control import cli  # noqa: E402
from osg_control.libero.articulation import (  # noqa: E402
    DOOR_REGIONS,
    DRAWER_REGIONS,
    KNOB_FIXTURES,
    implied_init,
)
from osg_control.libero.operators import SCHEMAS, achievers  # noqa: E402
from osg_control.libero.pddl_export import UnsupportedPredicateError  # noqa: E402
from osg_control.libero.plan import plan_task  # noqa: E402
from osg_control.libero.problem import Atom, LiberoProblem  # noqa: E402
from osg_control.libero.suites import suite_names  # noqa: E402
from osg_control.libero.tasks import task_count, task_problem  # noqa: E402
from osg_control.planning.api import plan_files  # noqa: E402
from osg_control.planning.fast_downward import find_fast_downward  # noqa: E402

BUILT_IN = "astar-hmax"
"""The built-in planner the sweep checks (A* with h_max: optimal, cheapest per state)."""


def test_every_task_file_is_planned_and_fast_downward_agrees() -> None:
    """All 160 tasks of the 16 suites: the built-in planner finds an optimal plan for each
    goal; Fast Downward (run alongside, its subprocesses in threads) the same cost. Prints
    per suite: tasks planned, plan lengths, the built-in planner's median time."""
    if find_fast_downward() is None:
        pytest.skip("Fast Downward (up-fast-downward) is not installed")
    problems = [task_problem(s, i) for s in suite_names() for i in range(task_count(s))]
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        downward = [pool.submit(plan_task, p, "fast-downward") for p in problems]
        built_in, seconds = [], []
        for problem in problems:
            started = time.perf_counter()
            built_in.append(plan_task(problem, BUILT_IN))
            seconds.append(time.perf_counter() - started)
        costs = [f.result().cost for f in downward]
    for problem, ours, theirs in zip(problems, built_in, costs, strict=True):
        where = f"{problem.suite}:{problem.index} {problem.name}"
        assert ours.status == "solved", (where, ours.unreached)
        assert ours.cost == theirs, where
    for suite in suite_names():
        mine = [(r, t) for p, r, t in zip(problems, built_in, seconds, strict=True)
                if p.suite == suite]  # fmt: skip
        lengths = sorted(len(r.steps or ()) for r, _ in mine)
        print(f"{suite}: {len(mine)}/{task_count(suite)} planned, steps {lengths}, median "
              f"{1000 * statistics.median(t for _, t in mine):.0f} ms ({BUILT_IN})")  # fmt: skip


def test_a_closed_drawer_is_opened_before_the_bowl_goes_in() -> None:
    """LIBERO-Goal task 3: the file leaves the top drawer closed; the plan opens it, then
    fetches the bowl and puts it in."""
    result = plan_task(task_problem("libero_goal", 3), BUILT_IN)
    actions = result.actions
    drawer = "wooden_cabinet_1_top_region"
    opened = actions.index(f"open {drawer} {drawer}")
    assert opened < actions.index(f"place-in akita_black_bowl_1 {drawer}") == len(actions) - 1
    assert any(a.startswith("pick akita_black_bowl_1 ") for a in actions[opened:])


def test_the_microwave_is_closed_after_the_mug_goes_in() -> None:
    """LIBERO-10 task 9: the door starts open (the file says so); the mug goes in first."""
    actions = plan_task(task_problem("libero_10", 9), BUILT_IN).actions
    assert actions[-1] == "close microwave_1 microwave_1_heating_region"
    assert "place-in white_yellow_mug_1 microwave_1_heating_region" in actions


def test_what_the_file_leaves_unsaid_comes_from_the_articulation_table() -> None:
    drawer = task_problem("libero_10", 3)  # the bottom drawer starts open
    unsaid = set(implied_init(drawer))
    assert Atom("close", ("white_cabinet_1_top_region",)) in unsaid
    assert Atom("close", ("white_cabinet_1_bottom_region",)) not in unsaid
    assert Atom("accessible", ("white_cabinet_1_bottom_region",)) in unsaid
    assert Atom("accessible", ("white_cabinet_1_top_region",)) not in unsaid
    stove = task_problem("libero_goal_task", 7)  # "turn off the stove": it starts off
    assert Atom("turnoff", ("flat_stove_1",)) in set(implied_init(stove))
    assert plan_task(stove, BUILT_IN).actions == ()


def _articulation(kind: str) -> tuple[tuple[str, ...], bool, bool]:
    """LIBERO's model of a fixture category, read as its env reads it: the regions whose
    site sits on a body with a joint (drawers: ``object_sites_dict[...].joints``), whether
    it opens as a whole, whether it turns on. A category without an object model (the
    tables and the floor are the scene's arena) moves nothing."""
    from libero.libero.envs.objects import get_object_dict

    if kind not in get_object_dict():
        return (), False, False
    fixture = get_object_dict()[kind](name=f"{kind}_1")
    jointed: dict[str, bool] = {}
    for part in fixture.worldbody.find("body").findall(".//body"):
        sites = part.findall(".//site")
        if not sites:
            break
        for site in sites:  # as LIBERO's problems do: the innermost body's joints win
            jointed[site.get("name")[len(kind) + 3 :]] = bool(part.findall("./joint"))
    ranges = fixture.object_properties.get("articulation", {})
    drawers = tuple(name for name, moves in jointed.items() if moves)
    opens = bool(ranges.get("default_open_ranges")) and not drawers
    return drawers, opens, bool(ranges.get("default_turnon_ranges"))


def test_the_articulation_table_is_libero_s_assets() -> None:
    """Every fixture category of the 16 suites: its drawers, door and knob as declared in
    ``articulation`` are what LIBERO's object models have."""
    kinds = sorted({kind for s in suite_names() for i in range(task_count(s))
                    for kind in task_problem(s, i).fixtures.values()})  # fmt: skip
    for kind in kinds:
        drawers, opens, turns = _articulation(kind)
        assert set(drawers) == set(DRAWER_REGIONS.get(kind, ())), kind
        assert opens == (kind in DOOR_REGIONS) and turns == (kind in KNOB_FIXTURES), kind
    assert {*DRAWER_REGIONS, *DOOR_REGIONS, *KNOB_FIXTURES} <= set(kinds)


def test_a_goal_predicate_no_operator_achieves_is_named() -> None:
    real = task_problem("libero_10", 0)
    odd = LiberoProblem(**{**real.__dict__, "goal": (Atom("stacked", ("milk_1", "butter_1")),)})
    named = r"no plan: .*'stacked' \(tasks libero_10:0"
    with pytest.raises(UnsupportedPredicateError, match=named):
        plan_task(odd)
    assert achievers()["in"] == ("place-in",) and achievers()["turnon"] == ("turn-on",)
    assert {s.name for s in SCHEMAS} >= {"pick", "place-on", "open", "close", "turn-off"}


def test_a_goal_on_something_nothing_moves_has_no_plan() -> None:
    """``(open basket_1_contain_region)``: ``open`` has an operator, but a basket has no
    door; the search proves there is no plan and names the goal atom."""
    real = task_problem("libero_10", 0)
    shut = LiberoProblem(**{**real.__dict__, "goal": (Atom("open", ("basket_1_contain_region",)),)})
    result = plan_task(shut, BUILT_IN)
    assert result.status == "unsolvable"
    assert result.unreached == ("(open basket_1_contain_region)",)


def test_export_writes_the_domain_the_problems_plan_on(tmp_path: Path, capsys) -> None:
    """``pddl export`` writes osg-libero.pddl beside the problems; the core's PDDL reader
    plans each pair to the cost of ``plan_task``; ``plan --json`` prints the same plan."""
    out = tmp_path / "goal"
    argv = ["--domain", "libero", "pddl", "export", "--suite", "libero_goal", "--task", "3", "5",
            "--out", str(out)]  # fmt: skip
    assert cli.main(argv) == 0
    files = sorted(out.glob("*.pddl"))
    assert [f.name for f in files][-1] == "osg-libero.pddl" and len(files) == 3
    domain_text = files[-1].read_text()
    assert "(:action place-in" in domain_text and "wine_bottle - movable" in domain_text
    for problem_file, index in zip(files[:2], (3, 5), strict=True):
        from_files = plan_files(files[-1], problem_file, BUILT_IN)
        assert from_files.cost == plan_task(task_problem("libero_goal", index), BUILT_IN).cost
    capsys.readouterr()
    argv = ["--domain", "libero", "plan", "--suite", "libero_goal", "--task", "3", "--json"]
    assert cli.main(argv) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["task"] == 3 and printed["status"] == "solved"
    assert len(printed["steps"]) == len(plan_task(task_problem("libero_goal", 3)).actions)


def test_plan_verb_refuses_a_task_outside_the_suite(capsys) -> None:
    assert cli.main(["--domain", "libero", "plan", "--suite", "libero_10", "--task", "10"]) == 2
    assert "tasks 0-9" in capsys.readouterr().err
