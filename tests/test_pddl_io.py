"""PDDL export/import: round trips, the committed domain, costs, goals, named parse errors."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from pddl.formatter import domain_to_string, problem_to_string

from osg_control.domain.registry import get_domain
from osg_control.errors import PDDLError, PlanningError
from osg_control.execution.bundle import measured_graph
from osg_control.kitchen.skills import NODES, SKILLS, WORLD_FACTS
from osg_control.kitchen.tasks import DEFAULT_WORLD, KITCHEN_TASKS
from osg_control.planning.graph import graph_from_specs
from osg_control.planning.pddl_io import (
    DEFAULT_COST,
    build_domain,
    build_problem,
    export_pddl,
    parse_atoms,
    skill_cost,
    task_problem,
    write_pddl,
)
from osg_control.planning.pddl_parse import read_domain, read_problem

REPO = Path(__file__).resolve().parents[1]
COMMITTED = REPO / "domains" / "kitchen"
KITCHEN = get_domain("kitchen")
MEASURED = build_domain(measured_graph(KITCHEN), "osg-kitchen", KITCHEN.lifting)


def _kitchen_pddl():  # type: ignore[no-untyped-def]
    return build_domain(graph_from_specs(KITCHEN), "osg-kitchen", KITCHEN.lifting)


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    return export_pddl(KITCHEN, tmp_path_factory.mktemp("pddl"), measured_graph(KITCHEN))


@pytest.mark.slow
def test_export_parse_export_is_stable(exported: list[Path], tmp_path: Path) -> None:
    domain = read_domain(exported[0])
    assert domain_to_string(domain) == domain_to_string(MEASURED.domain)
    again = write_pddl(domain, tmp_path / "again.pddl")
    assert domain_to_string(read_domain(again)) == domain_to_string(domain)
    for task, path in zip(KITCHEN_TASKS, exported[1:], strict=True):
        problem = read_problem(path)
        assert problem_to_string(problem) == problem_to_string(
            task_problem(MEASURED, KITCHEN, task)
        )


def test_committed_domain_and_problems_are_up_to_date(exported: list[Path]) -> None:
    for path in exported:
        committed = COMMITTED / path.relative_to(exported[0].parent)
        assert committed.read_text() == path.read_text(), f"regenerate {committed}"


def test_domain_has_one_typed_operator_per_skill_with_effects_and_cost() -> None:
    domain = _kitchen_pddl().domain
    assert domain.name == "osg-kitchen"
    assert {str(r) for r in domain.requirements} == {":strips", ":typing", ":action-costs"}
    assert {a.name for a in domain.actions} == {s.name for s in SKILLS}
    assert set(domain.types) == {"node", "cube", "door", "handle", "valve"}
    # the nodes, and the only instances an operator names itself (not through a parameter)
    assert {c.name for c in domain.constants} == {*NODES, "door-1", "handle-1"}
    assert {p.name for p in domain.predicates} == {
        "at", "at-object", *(p.name for p in KITCHEN.predicates)
    }  # fmt: skip
    text = domain_to_string(domain)
    assert (
        "(:action slide-door-open\n        :parameters (?d - door)\n"
        "        :precondition (and (at-object handle ?d) (door-closed ?d) (holding handle-1))\n"
        "        :effect (and (door-open ?d) (not (door-closed ?d)) "
        "(at handle-open) (not (at-object handle ?d)) "
        f"(increase (total-cost) {DEFAULT_COST}))"
    ) in text
    assert (
        "(:action grab-cube\n        :parameters (?c - cube)\n"
        "        :precondition (and (at-object above-cube ?c) (on-counter ?c) (hand-empty))\n"
        "        :effect (and (holding ?c) (not (hand-empty)) (at-object cube-grasped ?c) "
        "(not (at-object above-cube ?c))"
    ) in text
    assert "(in-cabinet ?c - cube)" in text and "(holding ?o)" in text


@pytest.mark.parametrize(
    ("rate", "cost"),
    [(None, DEFAULT_COST), (1.0, 1), (0.999999, 1), (0.5, 693), (0.9, 105), (0.0, 6908)],
)
def test_skill_cost_scale(rate: float | None, cost: int) -> None:
    assert skill_cost(rate) == cost


def test_success_rates_set_operator_costs() -> None:
    graph = graph_from_specs(KITCHEN, success_rates={"grab-cube": 0.8})
    text = domain_to_string(build_domain(graph).domain)
    grab = text[text.index("(:action grab-cube") :]
    assert f"(increase (total-cost) {round(-math.log(0.8) * 1000)})" in grab.split("(:action")[1]


def test_problem_names_its_objects_init_goal_and_metric() -> None:
    problem = build_problem(
        _kitchen_pddl(), "door-front", DEFAULT_WORLD, "door-open (in-cabinet cube-1) (at home)"
    )
    text = problem_to_string(problem)
    assert "(:objects cube-1 - cube valve-1 - valve)" in text  # door-1, handle-1: constants
    assert (
        "(:init (= (total-cost) 0) (at door-front) (door-closed door-1) (hand-empty) "
        "(on-counter cube-1) (valve-closed valve-1))"
    ) in text
    assert "(:goal (and (door-open door-1) (in-cabinet cube-1) (at home)))" in text
    assert "(:metric minimize (total-cost))" in text
    anchored = problem_to_string(build_problem(_kitchen_pddl(), "above-cube", (), "(at home)"))
    assert "(at-object above-cube cube-1)" in anchored


def test_parse_atoms_forms() -> None:
    assert parse_atoms("door-open (cube-in-cabinet)  (at home)") == (
        ("door-open",),
        ("cube-in-cabinet",),
        ("at", "home"),
    )
    assert parse_atoms(["door-open", "door-open"]) == (("door-open",),)
    with pytest.raises(PlanningError, match="cannot read atoms"):
        parse_atoms("(at home")
    with pytest.raises(PlanningError, match="empty atom"):
        parse_atoms("()")


def test_unknown_goal_fact_lists_known_ones() -> None:
    with pytest.raises(PlanningError) as err:
        build_problem(_kitchen_pddl(), "home", DEFAULT_WORLD, "door-opn")
    assert "unknown predicate 'door-opn'" in str(err.value)
    assert all(fact in str(err.value) for fact in WORLD_FACTS)
    with pytest.raises(PlanningError, match="unknown object 'cube-2'"):
        build_problem(_kitchen_pddl(), "home", DEFAULT_WORLD, "(lifted cube-2)")
    with pytest.raises(PlanningError, match="'lifted' takes 1 argument"):
        build_problem(_kitchen_pddl(), "home", DEFAULT_WORLD, "(lifted cube-1 door-1)")
    with pytest.raises(PlanningError, match="'door-1' in \\(lifted door-1\\) is a door"):
        build_problem(_kitchen_pddl(), "home", DEFAULT_WORLD, "(lifted door-1)")


def test_unknown_node_lists_known_nodes() -> None:
    with pytest.raises(PlanningError) as err:
        build_problem(_kitchen_pddl(), "kitchen-sink", DEFAULT_WORLD, "door-open")
    assert "unknown node 'kitchen-sink'" in str(err.value)
    assert all(node in str(err.value) for node in NODES)
    with pytest.raises(PlanningError, match="takes 1 argument"):
        build_problem(_kitchen_pddl(), "home", DEFAULT_WORLD, "(at)")
    with pytest.raises(PlanningError, match="empty goal"):
        build_problem(_kitchen_pddl(), "home", DEFAULT_WORLD, "")


def _broken_copy(source: Path, tmp_path: Path, old: str, new: str) -> Path:
    text = source.read_text()
    assert old in text
    path = tmp_path / source.name
    path.write_text(text.replace(old, new, 1))
    return path


def test_syntax_error_names_file_line_and_expectation(exported: list[Path], tmp_path: Path) -> None:
    path = _broken_copy(exported[0], tmp_path, "(hand-empty) (holding ?o)", "(hand-empty (")
    line = next(i for i, t in enumerate(path.read_text().splitlines(), 1) if "(hand-empty (" in t)
    with pytest.raises(PDDLError) as err:
        read_domain(path)
    message = str(err.value)
    assert message.startswith(f"{path}:{line}:")
    assert "expected" in message and "')'" in message


def test_undefined_constant_names_its_line(exported: list[Path], tmp_path: Path) -> None:
    path = _broken_copy(exported[0], tmp_path, "(at home) (hand-empty)", "(at hom) (hand-empty)")
    line = next(i for i, t in enumerate(path.read_text().splitlines(), 1) if "(at hom)" in t)
    with pytest.raises(PDDLError, match=rf"^{path}:{line}: .*'hom'"):
        read_domain(path)


def test_truncated_problem_and_missing_file(exported: list[Path], tmp_path: Path) -> None:
    path = tmp_path / "cut.pddl"
    path.write_text(exported[1].read_text().rstrip()[:-1])
    with pytest.raises(PDDLError, match="end of file"):
        read_problem(path)
    with pytest.raises(PDDLError, match="not found"):
        read_domain(tmp_path / "nope.pddl")
