"""The planner: kitchen plans, optimality against exhaustive search and Fast Downward, errors."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from pddl.core import Domain, Problem

from osg_control.cli import main
from osg_control.commands.plan import PLANNER_NAMES
from osg_control.domain.base import Domain as OSGDomain
from osg_control.domain.base import Task as KitchenTask
from osg_control.domain.binding import recorded
from osg_control.domain.registry import get_domain
from osg_control.errors import PDDLError, PlanningError
from osg_control.execution.bundle import read_manifest
from osg_control.kitchen.tasks import DEFAULT_WORLD, KITCHEN_TASKS
from osg_control.planning.api import (
    PLANNERS,
    graph_domain,
    plan_files,
    plan_for_goal,
    plan_on_graph,
    solve,
)
from osg_control.planning.fast_downward import find_fast_downward
from osg_control.planning.graph import graph_from_specs
from osg_control.planning.grounding import ground
from osg_control.planning.heuristics import HMax
from osg_control.planning.memo import PlanMemo
from osg_control.planning.pddl_io import (
    build_domain,
    build_problem,
    skill_cost,
)
from osg_control.planning.pddl_parse import read_domain, read_problem
from osg_control.planning.synthetic import random_goal, random_skill_graph
from osg_control.planning.task import State, Task

KITCHEN = get_domain("kitchen")
REPO = Path(__file__).resolve().parents[1]
DOMAIN = REPO / "domains" / "kitchen" / "osg-kitchen.pddl"
PROBLEMS = sorted((REPO / "domains" / "kitchen" / "problems").glob("*.pddl"))
needs_fd = pytest.mark.skipif(
    find_fast_downward() is None,
    reason="Fast Downward driver (up_fast_downward/downward/fast-downward.py) not installed",
)


def _bound(*names: str) -> tuple[str, ...]:
    """Kitchen skills as plan steps: each bound to the kitchen's one object of its type."""
    return tuple(recorded(KITCHEN.lifting, KITCHEN.skill(name)).label for name in names)


OPEN = _bound("move-home-to-door", "grab-handle", "slide-door-open", "release-handle")
PICK = _bound("grab-cube", "pick-up-cube")
PLACE = _bound("move-cube-to-cabinet", "place-cube-in-cabinet", "release-cube")
EXPECTED_FROM_HOME = {
    "pick-up": (*_bound("move-home-to-cube"), *PICK),
    "open-door": OPEN,
    "open-pick-up": (*OPEN, *_bound("move-cabinet-to-cube"), *PICK),
    "pick-up-place": (*_bound("move-home-to-cube"), *PICK, *PLACE),
    "open-pick-up-place": (*OPEN, *_bound("move-cabinet-to-cube"), *PICK, *PLACE),
    "turn-valve": _bound("move-home-to-valve", "lower-to-valve", "push-valve-open"),
    "open-door-turn-valve": (
        *OPEN,
        *_bound("move-cabinet-to-home", "move-home-to-valve", "lower-to-valve"),
        *_bound("push-valve-open"),
    ),
}
"""The kitchen's tasks from home: the unique cheapest plans (all skills cost the same)."""
ONE_CUBE = [task for task in KITCHEN_TASKS if not task.counts]
"""The tasks of the one-cube kitchen (the others run in the kitchen with their cubes)."""


def test_default_goal_gives_the_ten_skill_plan() -> None:
    result = plan_for_goal(KITCHEN, "door-open cube-in-cabinet")
    assert result.actions == EXPECTED_FROM_HOME["open-pick-up-place"]
    assert result.cost == 1000
    assert result.stats.expanded > 0 and result.stats.time_s >= 0


@pytest.mark.parametrize("task", ONE_CUBE, ids=lambda t: t.name)
def test_kitchen_tasks_from_home(task: KitchenTask) -> None:
    assert (
        plan_for_goal(KITCHEN, task.goal, task.node, task.world).actions
        == EXPECTED_FROM_HOME[task.name]
    )


def test_two_cube_tasks_from_home_handle_each_cube_once() -> None:
    pick = plan_for_goal(KITCHEN.for_task(KITCHEN.task("pick-up-cube-2")), "(lifted cube-2)")
    assert pick.actions == ("move-home-to-cube cube-2", "grab-cube cube-2", "pick-up-cube cube-2")
    task = KITCHEN.task("two-cubes-in-cabinet")
    both = plan_for_goal(KITCHEN.for_task(task), task.goal, task.node, task.world)
    assert len(both.actions) == len(OPEN) + 2 * (1 + len(PICK) + len(PLACE))
    for cube in ("cube-1", "cube-2"):
        assert sum(step.endswith(cube) for step in both.actions) == 1 + len(PICK) + len(PLACE)


def _kitchen_task(
    node: str, world: tuple[str, ...], goal: tuple[str, ...], domain: OSGDomain = KITCHEN
) -> Task:
    pddl = build_domain(graph_from_specs(domain), "osg-kitchen", domain.lifting)
    return ground(pddl.domain, build_problem(pddl, node, world, goal))


@pytest.mark.parametrize("node", ["door-front", "above-cube", "cabinet-front", "handle"])
@pytest.mark.parametrize("task", KITCHEN_TASKS, ids=lambda t: t.name)
def test_kitchen_tasks_from_other_nodes_reach_the_goal_optimally(
    task: KitchenTask, node: str
) -> None:
    world = task.world
    if node == "handle":  # at the handle the robot holds it, the door still shut
        world = ("door-closed", "cube-on-counter", "holding-handle")
    scene = KITCHEN.for_task(task)
    astar = plan_for_goal(scene, task.goal, node, world)
    ucs = plan_for_goal(scene, task.goal, node, world, planner="ucs")
    sim = _kitchen_task(node, world, task.goal, scene)
    if not astar.solved:  # e.g. open-door from above-cube: fine, but then UCS must agree
        assert not ucs.solved and astar.unreached
        return
    assert astar.cost == ucs.cost
    final = sim.simulate(astar.actions)  # checks each step's preconditions on the way
    assert sim.goal <= final


def test_a_remembered_plan_is_the_planners_own_answer() -> None:
    """``PlanMemo`` answers each question once, the same as ``plan_for_goal``: the facts'
    order does not matter, a different node, goal or planner is a new question."""
    pddl = graph_domain(KITCHEN)
    memo = PlanMemo(KITCHEN, pddl)
    for task in ONE_CUBE:
        for node in ("home", "door-front", "above-cube"):
            fresh = plan_for_goal(KITCHEN, task.goal, node, task.world, "astar", pddl=pddl)
            remembered = memo(task.goal, node, task.world, "astar")
            assert (remembered.steps, remembered.cost, remembered.unreached) == (
                fresh.steps,
                fresh.cost,
                fresh.unreached,
            )
    questions = len(ONE_CUBE) * 3
    assert memo.asked() == (0, questions)
    task = KITCHEN_TASKS[0]
    first = memo(task.goal, "home", task.world, "astar")
    assert memo(task.goal, "home", reversed(task.world), "astar") is first
    assert memo.asked() == (2, questions)
    memo(task.goal, "home", task.world, "ucs")
    assert memo.asked() == (2, questions + 1)


def test_plan_simulated_step_by_step() -> None:
    task = _kitchen_task("home", DEFAULT_WORLD, ("door-open", "cube-in-cabinet"))
    state = task.init
    for name in EXPECTED_FROM_HOME["open-pick-up-place"]:
        op = task.operator(name)
        assert op.applicable(state), name
        state = op.apply(state)
    assert task.goal <= state
    assert "(at cabinet-front)" in state and "(hand-empty)" in state
    assert "(in-cabinet cube-1)" in state and "(door-open door-1)" in state
    with pytest.raises(PlanningError, match="preconditions"):
        task.simulate(["grab-cube cube-1"])


def test_unreachable_goal_gives_no_plan_naming_the_facts() -> None:
    for planner in ("astar", "ucs"):
        result = plan_for_goal(
            KITCHEN, "cube-in-cabinet", world=("door-closed", "hand-empty"), planner=planner
        )
        assert not result.solved and result.cost is None
        assert result.unreached == ("(in-cabinet cube-1)",)


def test_goal_blocked_by_deletes_lists_unmet_facts() -> None:
    # Both facts are reachable when deletes are ignored, never together.
    result = plan_for_goal(KITCHEN, "door-open door-closed")
    assert not result.solved
    assert result.unreached == ("(door-open door-1)",)


def test_success_rates_steer_the_plan() -> None:
    rates = {"move-home-to-door": 0.5, "move-door-to-home": 0.5}
    result = plan_for_goal(
        KITCHEN,
        "(at door-front)",
        node="home",
        graph=graph_from_specs(KITCHEN, success_rates=rates),
    )
    assert result.actions == ("move-home-to-door door-1",)
    assert result.cost == round(-math.log(0.5) * 1000)


def _brute_force_cost(task: Task, depth: int) -> float:
    """Cheapest goal-reaching cost over every operator sequence up to ``depth`` long."""
    best = math.inf

    def walk(state: State, cost: float, left: int) -> None:
        nonlocal best
        if cost >= best:
            return
        if task.goal <= state:
            best = cost
            return
        if left:
            for op in task.operators:
                if op.applicable(state):
                    walk(op.apply(state), cost + op.cost, left - 1)

    walk(task.init, 0.0, depth)
    return best


@pytest.mark.parametrize("seed", range(16))
def test_astar_matches_exhaustive_search_on_random_graphs(seed: int) -> None:
    graph = random_skill_graph(12, num_facts=2, seed=seed)
    goal = random_goal(graph, seed=seed, num_goal_facts=1 + seed % 2)
    pddl = build_domain(graph)
    domain, problem = pddl.domain, build_problem(pddl, goal.node, goal.world, goal.goal)
    astar, ucs = solve(domain, problem, "astar"), solve(domain, problem, "ucs")
    depth = 7
    expected = _brute_force_cost(ground(domain, problem), depth)
    cost = math.inf if astar.cost is None else astar.cost
    assert astar.cost == ucs.cost
    assert cost <= expected  # nothing cheaper hides among the short sequences
    if len(astar.actions) <= depth:
        assert cost == expected


@pytest.mark.parametrize("seed", range(6))
def test_hmax_is_admissible(seed: int) -> None:
    graph = random_skill_graph(40, seed=seed)
    goal = random_goal(graph, seed=seed, num_goal_facts=2)
    pddl = build_domain(graph)
    domain, problem = pddl.domain, build_problem(pddl, goal.node, goal.world, goal.goal)
    task = ground(domain, problem)
    result = solve(domain, problem, "ucs")
    h = HMax(task)(task.init)
    assert h <= (math.inf if result.cost is None else result.cost)


@pytest.mark.slow
@needs_fd
@pytest.mark.parametrize("problem", PROBLEMS, ids=lambda p: p.stem)
def test_astar_and_fast_downward_agree_on_committed_problems(problem: Path) -> None:
    astar = plan_files(DOMAIN, problem, "astar")
    fd = plan_files(DOMAIN, problem, "fast-downward")
    assert fd.solved and fd.cost == astar.cost
    assert fd.stats.time_s > 0


@needs_fd
@pytest.mark.parametrize("seed", range(3))
def test_astar_and_fast_downward_agree_on_random_problems(seed: int) -> None:
    graph = random_skill_graph(30, seed=seed)
    goal = random_goal(graph, seed=seed, num_goal_facts=2)
    results = [
        plan_on_graph(graph, goal.goal, goal.node, goal.world, p)
        for p in ("astar", "fast-downward")
    ]
    assert results[0].cost == results[1].cost
    assert results[0].unreached == results[1].unreached


COURIER_DOMAIN = """
(define (domain courier)
  (:requirements :strips :typing :action-costs)
  (:types place parcel - object hub - place)
  (:predicates (van-at ?p - place) (at ?x - parcel ?p - place) (in ?x - parcel)
               (road ?a ?b - place))
  (:functions (total-cost))
  (:action drive
    :parameters (?a ?b - place)
    :precondition (and (van-at ?a) (road ?a ?b))
    :effect (and (van-at ?b) (not (van-at ?a)) (increase (total-cost) 2)))
  (:action express
    :parameters (?a - place ?h - hub)
    :precondition (van-at ?a)
    :effect (and (van-at ?h) (not (van-at ?a)) (increase (total-cost) 5)))
  (:action load
    :parameters (?x - parcel ?p - place)
    :precondition (and (van-at ?p) (at ?x ?p))
    :effect (and (in ?x) (not (at ?x ?p)) (increase (total-cost) 1)))
  (:action unload
    :parameters (?x - parcel ?h - hub)
    :precondition (and (van-at ?h) (in ?x))
    :effect (and (at ?x ?h) (not (in ?x)) (increase (total-cost) 1))))
"""
COURIER_PROBLEM = """
(define (problem two-parcels)
  (:domain courier)
  (:objects a b c d - place depot - hub p1 p2 - parcel)
  (:init (van-at depot) (at p1 a) (at p2 d) (= (total-cost) 0)
    (road depot a) (road a b) (road b c) (road c d) (road d c))
  (:goal (and (at p1 depot) (at p2 depot)))
  (:metric minimize (total-cost)))
"""


@pytest.fixture()
def courier(tmp_path: Path) -> tuple[Path, Path]:
    (tmp_path / "domain.pddl").write_text(COURIER_DOMAIN)
    (tmp_path / "problem.pddl").write_text(COURIER_PROBLEM)
    return tmp_path / "domain.pddl", tmp_path / "problem.pddl"


def test_typed_domain_with_parameters(courier: tuple[Path, Path]) -> None:
    result = plan_files(*courier)
    # drive to a (2), load (1), drive a-b-c-d (6), load (1), express home (5), unload x2 (2)
    assert result.cost == 17
    assert result.actions[:2] == ("drive depot a", "load p1 a")
    assert plan_files(*courier, planner="ucs").cost == 17
    task = ground(*_read(courier))
    assert not any(op.name.startswith("unload p1 a") for op in task.operators)  # a: no hub
    assert "drive a depot" not in {op.name for op in task.operators}  # no such road


def _read(files: tuple[Path, Path]) -> tuple[Domain, Problem]:
    return read_domain(files[0]), read_problem(files[1])


@needs_fd
def test_fast_downward_on_typed_domain(courier: tuple[Path, Path]) -> None:
    assert plan_files(*courier, planner="fast-downward").cost == 17


@pytest.mark.parametrize(
    ("old", "new", "named"),
    [
        (
            "(and (van-at ?a) (road ?a ?b))",
            "(or (van-at ?a) (road ?a ?b))",
            r"domain.pddl:10: 'or' needs :disjunctive-preconditions",
        ),
        (
            "(van-at ?b) (not (van-at ?a))",
            "(when (van-at ?a) (van-at ?b))",
            r"domain.pddl:11: 'when' needs :conditional-effects",
        ),
        (
            "(increase (total-cost) 2)",
            "(increase (total-cost) (+ 1 1))",
            r"domain.pddl:11: '\+' in an action cost needs :numeric-fluents",
        ),
    ],
)
def test_unsupported_constructs_are_named_with_line(
    courier: tuple[Path, Path], old: str, new: str, named: str
) -> None:
    domain_file = courier[0]
    domain_file.write_text(COURIER_DOMAIN.replace(old, new, 1))
    with pytest.raises(PDDLError, match=named):
        plan_files(*courier)


def test_unit_costs_without_metric(courier: tuple[Path, Path]) -> None:
    courier[1].write_text(COURIER_PROBLEM.replace("(:metric minimize (total-cost))", ""))
    result = plan_files(*courier)
    assert all(step.cost == 1 for step in result.steps or ())
    # drive to a, load, drive a-b-c-d, load, express to the depot, unload twice: 9 steps
    assert result.cost == 9 == plan_files(*courier, planner="ucs").cost


def test_unknown_planner_and_goal_are_named() -> None:
    with pytest.raises(PlanningError, match="known planners: auto, astar, astar-hmax"):
        plan_for_goal(KITCHEN, "door-open", planner="magic")
    assert set(PLANNERS) == set(PLANNER_NAMES)
    with pytest.raises(PlanningError, match="known predicates: .*door-open"):
        plan_for_goal(KITCHEN, "door-ajar")


def test_cli_plan_json_and_exit_codes(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", "--goal", "door-open cube-in-cabinet", "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert [s["action"] for s in payload["steps"]] == list(EXPECTED_FROM_HOME["open-pick-up-place"])
    rates = read_manifest(KITCHEN.defaults_dir)["success_rates"]  # the shipped costs
    assert payload["solved"]
    skills = [s["action"].split()[0] for s in payload["steps"]]
    assert payload["cost"] == sum(skill_cost(rates[name]) for name in skills)
    assert main(["plan", "--goal", "cube-lifted", "--facts", "door-closed hand-empty"]) == 3
    assert "goal facts unreached: (lifted cube-1)" in capsys.readouterr().out
    assert main(["plan", "--goal", "door-ajar"]) == 2  # refused before planning: a usage error
    assert "unknown predicate 'door-ajar'" in capsys.readouterr().err
    assert main(["plan", str(DOMAIN), str(PROBLEMS[0]), "--planner", "ucs"]) == 0
    assert "plan for" in capsys.readouterr().out
    assert main(["plan", str(DOMAIN)]) == 1
    assert "got 1 file(s)" in capsys.readouterr().err


def test_cli_pddl_export(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["pddl", "export", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "osg-kitchen.pddl").read_text() == DOMAIN.read_text()
    assert sorted(p.name for p in (tmp_path / "problems").iterdir()) == [p.name for p in PROBLEMS]
