"""Typed objects and lifted skills: the kitchen's declarations, their validation, plan steps
bound to instances, synthetic multi-cube problems, goals as atoms on the command line."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from osg_control.cli import main
from osg_control.domain.base import Task
from osg_control.domain.binding import bind, bind_step, recorded
from osg_control.domain.lifted import FactAtom, ObjectInstance, PredicateDecl
from osg_control.domain.registry import get_domain
from osg_control.domain.spec import TOP_DOWN_QUAT
from osg_control.environment.success import GRIPPER_OPEN_CMD
from osg_control.errors import DomainError, PlanningError
from osg_control.execution.defaults import load_defaults
from osg_control.execution.executor import Executor
from osg_control.execution.goals import parse_goal
from osg_control.execution.objects import ObjectTracker
from osg_control.perception.percept import Percept
from osg_control.planning.api import graph_domain, plan_files, plan_for_goal, solve
from osg_control.planning.fast_downward import find_fast_downward
from osg_control.planning.graph import graph_from_specs
from osg_control.planning.pddl_io import build_problem, export_pddl, write_pddl
from osg_control.planning.synthetic import with_instances

KITCHEN = get_domain("kitchen")
REPO = Path(__file__).resolve().parents[1]
needs_fd = pytest.mark.skipif(find_fast_downward() is None, reason="Fast Downward not installed")


def _three_cubes():  # type: ignore[no-untyped-def]
    """The kitchen's lifted skills over three cubes, the two extra ones located by frames
    of their own (planning and binding only: the env has one cube)."""
    domain = with_instances(KITCHEN, "cube", 3)
    cube = KITCHEN.objects[0]
    frames = tuple(
        dataclasses.replace(cube, name=f"cube-{i}", held_fact=f"(holding cube-{i})") for i in (2, 3)
    )
    instances = tuple(
        dataclasses.replace(i, frame=i.name) if i.name in ("cube-2", "cube-3") else i
        for i in domain.instances
    )
    return dataclasses.replace(domain, objects=(*KITCHEN.objects, *frames), instances=instances)


THREE = _three_cubes()
WORLD = [*KITCHEN.start_world, "(on-counter cube-2)", "(on-counter cube-3)"]
ALL_IN = "(door-open door-1) (in-cabinet cube-1) (in-cabinet cube-2) (in-cabinet cube-3)"


def test_each_fact_is_declared_once_as_an_atom() -> None:
    lifting = KITCHEN.lifting
    assert {f.name for f in KITCHEN.fact_atoms} == set(KITCHEN.facts)
    assert lifting.atom("cube-lifted") == ("lifted", "cube-1")
    assert lifting.atom("(door-open)") == ("door-open", "door-1")  # today's 0-ary spelling
    assert lifting.atom("(lifted cube-1)") == ("lifted", "cube-1")
    assert lifting.fact(("lifted", "cube-1")) == "cube-lifted"
    assert lifting.fact(("lifted", "cube-2")) == "(lifted cube-2)"  # no name declared
    assert lifting.place("above-cube") == ("at-object", "above-cube", "cube-1")
    assert lifting.place("home") == ("at", "home")


def test_skills_are_lifted_over_their_parameters() -> None:
    grab = KITCHEN.lifting.skills["grab-cube"]
    assert grab.parameters == (("?c", "cube"),) and grab.recorded == {"?c": "cube-1"}
    assert grab.start == ("at-object", "above-cube", "?c")
    assert set(grab.pre) == {("hand-empty",), ("on-counter", "?c")}
    assert grab.add == (("holding", "?c"),)
    place = KITCHEN.lifting.skills["place-cube-in-cabinet"]
    assert ("door-open", "door-1") in place.pre  # the door is no parameter: a constant
    assert KITCHEN.lifting.constants() == ["door-1", "handle-1"]
    franka = get_domain("franka-kitchen").lifting
    assert not franka.lifted  # 0-ary facts: a lifted domain without objects
    assert all(not s.parameters for s in franka.skills.values())


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"instances": (ObjectInstance("cube-1", "box"),)}, "unknown type 'box'"),
        (
            {"instances": (*KITCHEN.instances, ObjectInstance("cube-1", "cube"))},
            r"declares \['cube-1'\] twice",
        ),
        (
            {"fact_atoms": (*KITCHEN.fact_atoms[:-1], FactAtom("valve-open", "valve-open"))},
            "fact 'valve-open': predicate 'valve-open' takes 1 argument",
        ),
        (
            {
                "fact_atoms": (
                    *KITCHEN.fact_atoms[:-1],
                    FactAtom("valve-open", "lifted", ("valve-1",)),
                )
            },
            "is a valve, not a cube",
        ),  # fmt: skip
        ({"types": {**KITCHEN.types, "cube": "box"}}, "unknown parent"),
        (
            {"predicates": (*KITCHEN.predicates, PredicateDecl("on", (("a", "plate"),)))},
            "unknown type 'plate'",
        ),
        (
            {
                "skills": (
                    dataclasses.replace(KITCHEN.skills[0], parameters=(("p", "plate"),)),
                    *KITCHEN.skills[1:],
                )
            },
            "parameter \\?p has type 'plate' without an instance",
        ),  # fmt: skip
        (
            {"instances": (ObjectInstance("cube-1", "cube", "lid"), *KITCHEN.instances[1:])},
            "names unknown object 'lid'",
        ),
        (
            {
                "objects": (
                    dataclasses.replace(KITCHEN.objects[0], held_fact="(holding cube-5)"),
                    *KITCHEN.objects[1:],
                )
            },
            r"field 'objects\[cube\].held_fact' names unknown fact '\(holding cube-5\)'",
        ),
    ],
)
def test_malformed_declarations_are_named(change: dict, message: str) -> None:
    with pytest.raises(DomainError, match=message):
        dataclasses.replace(KITCHEN, **change)


def test_a_plan_step_binds_the_skill_to_its_object() -> None:
    lifting, skills = THREE.lifting, THREE.skills_by_name
    same = bind_step(lifting, skills, "grab-cube cube-1")
    assert same.skill is skills["grab-cube"] and same.frames == {} and same.facts == {}
    other = bind_step(lifting, skills, "pick-up-cube cube-2")
    assert other.skill.name == "pick-up-cube"  # the lifted skill's policy runs
    assert other.skill.preconditions == {"(holding cube-2)", "(on-counter cube-2)"}
    assert other.skill.add_effects == {"(lifted cube-2)"}
    assert other.fact("holding-cube") == "(holding cube-2)"  # which cube a watch follows
    assert other.frames == {"cube": "cube-2"}
    seen = other.offsets({"cube": "one", "cube-2": "two"})
    assert seen["cube"] == "two"  # the policy acts in cube-2's frame
    assert recorded(lifting, skills["grab-cube"]).label == "grab-cube cube-1"
    with pytest.raises(PlanningError, match=r"\?c must be a cube, got 'door-1'"):
        bind(lifting, skills["grab-cube"], ["door-1"])
    with pytest.raises(PlanningError, match="takes 1 object"):
        bind_step(lifting, skills, "grab-cube")
    with pytest.raises(PlanningError, match="names no skill"):
        bind_step(lifting, skills, "juggle cube-1")


def test_three_cubes_are_planned_with_every_step_bound() -> None:
    result = plan_for_goal(THREE, ALL_IN, "home", WORLD)
    assert result.solved and len(result.actions) == 4 + 3 * 6
    for cube in ("cube-1", "cube-2", "cube-3"):
        steps = [a for a in result.actions if a.endswith(cube)]
        assert [s.split()[0] for s in steps] == [
            "move-cabinet-to-cube", "grab-cube", "pick-up-cube", "move-cube-to-cabinet",
            "place-cube-in-cabinet", "release-cube",
        ]  # fmt: skip
    assert plan_for_goal(THREE, ALL_IN, "home", WORLD, "ucs").cost == result.cost
    one = plan_for_goal(THREE, "(lifted cube-3)", "home", WORLD)
    assert one.actions == ("move-home-to-cube cube-3", "grab-cube cube-3", "pick-up-cube cube-3")
    goal = parse_goal("(in-cabinet cube-2) (lifted cube-1)", THREE)
    assert goal.facts == {"(in-cabinet cube-2)", "cube-lifted"}


@needs_fd
def test_fast_downward_agrees_on_three_cubes(tmp_path: Path) -> None:
    pddl = graph_domain(THREE)
    problem = build_problem(pddl, "home", WORLD, ALL_IN, name="three-cubes")
    files = (
        write_pddl(pddl.domain, tmp_path / "domain.pddl"),
        write_pddl(problem, tmp_path / "problem.pddl"),
    )
    ours = solve(pddl.domain, problem, "astar-hmax")
    fd = plan_files(*files, planner="fast-downward")
    assert fd.cost == ours.cost and fd.solved
    assert plan_files(*files, planner="astar").cost == ours.cost  # the files read back


def test_cli_goals_are_atoms(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", "--goal", "(door-open) (in-cabinet cube-1)", "--json"]) == 0
    atoms = json.loads(capsys.readouterr().out)
    assert atoms["goal"] == ["(door-open door-1)", "(in-cabinet cube-1)"]
    assert main(["plan", "--goal", "door-open cube-in-cabinet", "--json"]) == 0  # bare names
    names = json.loads(capsys.readouterr().out)
    assert (names["goal"], names["steps"]) == (atoms["goal"], atoms["steps"])
    for goal, named in (
        ("(in-cabinet cube-2)", "unknown object 'cube-2'"),
        ("(lifted)", "predicate 'lifted' takes 1 argument(s), got 0"),
        ("(lifted cube-1 cube-1)", "takes 1 argument(s), got 2"),
        ("(stacked cube-1)", "unknown predicate 'stacked'"),
        ("(at nowhere)", "unknown node 'nowhere'"),
    ):
        assert main(["plan", "--goal", goal]) == 2, goal
        assert named in capsys.readouterr().err, goal
    assert (
        main(["plan", "--goal", "(lifted cube-1)", "--facts", "hand-empty (on-counter cube-1)"])
        == 0
    )


def test_a_problem_file_naming_an_unknown_object_exits_5(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    committed = REPO / "domains" / "kitchen" / "problems" / "pick-up.pddl"
    broken = tmp_path / "pick-up.pddl"
    broken.write_text(
        committed.read_text().replace("(:goal (lifted cube-1))", "(:goal (lifted cube-9))")
    )
    line = next(i for i, t in enumerate(broken.read_text().splitlines(), 1) if "cube-9" in t)
    domain = REPO / "domains" / "kitchen" / "osg-kitchen.pddl"
    assert main(["plan", str(domain), str(broken)]) == 5
    assert f"{broken}:{line}: undeclared object 'cube-9'" in capsys.readouterr().err


def test_the_executor_plans_steps_bound_to_another_cube() -> None:
    defaults = load_defaults(KITCHEN)  # one policy per lifted skill: the shipped ones
    executor = Executor(THREE, defaults.policies, defaults.classifier, graph_from_specs(THREE))
    obs = np.zeros(10)
    obs[:3], obs[3:7], obs[7] = THREE.nodes["home"].position, TOP_DOWN_QUAT, GRIPPER_OPEN_CMD
    entry, plan, _ = executor.plan(["(lifted cube-2)"], obs, set(WORLD))
    assert entry is None
    assert plan == ["move-home-to-cube cube-2", "grab-cube cube-2", "pick-up-cube cube-2"]
    steps = [bind_step(THREE.lifting, THREE.skills_by_name, step) for step in plan]
    assert steps[-1].fact("holding-cube") == "(holding cube-2)"  # what run_skill watches
    assert all(step.frames == {"cube": "cube-2"} for step in steps)


def test_the_object_tracker_follows_which_cube_is_held() -> None:
    tracker = ObjectTracker(THREE)
    index = {name: i for i, name in enumerate(THREE.world_fields)}
    state = np.zeros(10)

    def seen(dx: float, facts: set[str]) -> Percept:
        world = np.zeros(len(THREE.world_fields))
        world[index["cube_x"]] = KITCHEN.objects[0].nominal[0] + dx
        world[index["cube_y"]] = KITCHEN.objects[0].nominal[1]
        return Percept(state=state, joints=np.zeros(7), world=world, facts=frozenset(facts))

    tracker.update(seen(0.05, {"hand-empty"}))
    tracker.update(seen(0.10, {"(holding cube-2)"}))  # cube-2 in the hand: frozen
    offsets = tracker.offsets()
    assert offsets["cube"][0] == pytest.approx(0.10)  # not held: it moved
    assert offsets["cube-2"][0] == pytest.approx(0.05)  # held: where it was picked up


def test_a_task_may_name_atoms_over_the_domains_objects(tmp_path: Path) -> None:
    two = Task("two-cubes-in-cabinet", ("door-open", "cube-in-cabinet", "(in-cabinet cube-2)"),
               world=tuple(WORLD), node="home")  # fmt: skip
    domain = dataclasses.replace(THREE, tasks=(two,))
    paths = export_pddl(domain, tmp_path)
    problem = paths[1].read_text()
    assert "(:goal (and (door-open door-1) (in-cabinet cube-1) (in-cabinet cube-2)))" in problem
    assert "(:objects cube-1 cube-2 cube-3 - cube valve-1 - valve)" in problem
    assert plan_files(*paths[:2]).cost == plan_for_goal(domain, two.goal, "home", WORLD).cost
    bad = Task("lost", ("(in-cabinet cube-9)",))
    with pytest.raises(DomainError, match=r"tasks\[lost\].goal' names unknown fact .*cube-9"):
        dataclasses.replace(THREE, tasks=(bad,))
