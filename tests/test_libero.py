"""The LIBERO domain with LIBERO's package (the ``libero`` extra; skipped without it): its
suites and task files, the PDDL problems written from them, its env at its fixed initial
states scored by its own ``check_success()``, and the benchmark harness."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from pddl.parser.problem import ProblemParser  # noqa: E402

from osg_control import cli  # noqa: E402
from osg_control.errors import ControllerError, UsageError  # noqa: E402
from osg_control.libero.benchmark import run_suite, summarise  # noqa: E402
from osg_control.libero.env import LiberoEnv  # noqa: E402
from osg_control.libero.operators import achievers  # noqa: E402
from osg_control.libero.pddl_export import UnsupportedPredicateError, export_problems  # noqa: E402
from osg_control.libero.problem import Atom, LiberoProblem  # noqa: E402
from osg_control.libero.suites import INIT_STATES, max_steps, suite_names  # noqa: E402
from osg_control.libero.tasks import (  # noqa: E402
    check_task_indices,
    init_states,
    task_count,
    task_problem,
)


def test_every_suite_parses_and_its_goals_have_operators() -> None:
    """All 16 suites' task files parse into typed problems whose goal predicates each have
    an operator; LIBERO-10's task 3 is read as the file states it."""
    for suite in suite_names():
        assert task_count(suite) == 10, suite
        for index in range(task_count(suite)):
            problem = task_problem(suite, index)
            assert problem.goal and {a.predicate for a in problem.goal} <= set(achievers())
    bowl = task_problem("libero_10", 3)
    assert bowl.objects["akita_black_bowl_1"] == "akita_black_bowl"
    assert bowl.fixtures["white_cabinet_1"] == "white_cabinet"
    assert bowl.regions["white_cabinet_1_bottom_region"].parent == "white_cabinet_1"
    assert set(bowl.goal) == {
        Atom("close", ("white_cabinet_1_bottom_region",)),
        Atom("in", ("akita_black_bowl_1", "white_cabinet_1_bottom_region")),
    }
    assert init_states("libero_10", 3).shape[0] == INIT_STATES


def test_swap_variant_moves_objects_between_regions() -> None:
    base, swap = task_problem("libero_10", 0), task_problem("libero_10_swap", 0)
    assert base.goal == swap.goal and base.init != swap.init


def test_export_writes_typed_problems_that_parse_back(tmp_path: Path, capsys) -> None:
    out = tmp_path / "pddl"
    assert cli.main(["--domain", "libero", "pddl", "export", "--suite", "libero_10",
                     "--out", str(out)]) == 0  # fmt: skip
    files = sorted(out.glob("*.pddl"))  # the ten problems, then the domain osg-libero.pddl
    assert len(files) == 11 and len(capsys.readouterr().out.splitlines()) == 11
    parsed = ProblemParser()(files[3].read_text().split("\n", 2)[2])
    objects = {o.name: set(o.type_tags) for o in parsed.objects}
    assert objects["akita_black_bowl_1"] == {"akita_black_bowl"}
    assert objects["white_cabinet_1_bottom_region"] == {"region"}
    goal = {str(g) for g in parsed.goal.operands}
    assert goal == {
        "(close white_cabinet_1_bottom_region)",
        "(in akita_black_bowl_1 white_cabinet_1_bottom_region)",
    }


def test_a_goal_predicate_without_operator_is_named_and_nothing_written(tmp_path: Path) -> None:
    real = task_problem("libero_10", 0)
    odd = LiberoProblem(**{**real.__dict__, "goal": (Atom("stacked", ("milk_1", "butter_1")),)})
    with pytest.raises(UnsupportedPredicateError, match="'stacked' .*libero_10:0"):
        export_problems([real, odd], tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_swap_variant_starts_the_objects_elsewhere(soup_env: LiberoEnv) -> None:
    """LIBERO-PRO's ``_swap``: the same goal, the soup starting where another object was."""
    swap = LiberoEnv("libero_10_swap", 0)
    try:
        moved = swap.reset(0)["alphabet_soup_1_pos"] - soup_env.reset(0)["alphabet_soup_1_pos"]
        assert np.linalg.norm(moved[:2]) > 0.05 and not swap.check_success()
    finally:
        swap.close()


def test_task_indices_are_checked() -> None:
    assert check_task_indices("libero_goal", None) == tuple(range(10))
    with pytest.raises(UsageError, match=r"tasks 0-9; got \[10\]"):
        check_task_indices("libero_goal", [0, 10])


@pytest.fixture(scope="module")
def soup_env():
    env = LiberoEnv("libero_10", 0)
    yield env
    env.close()


def test_initial_states_are_fixed_and_distinct(soup_env: LiberoEnv) -> None:
    first = soup_env.reset(0)["alphabet_soup_1_pos"]
    other = soup_env.reset(1)["alphabet_soup_1_pos"]
    again = soup_env.reset(0)["alphabet_soup_1_pos"]
    assert np.array_equal(first, again) and np.linalg.norm(first - other) > 1e-3
    assert not soup_env.check_success() and soup_env.steps == 0
    with pytest.raises(UsageError, match="outside 0-49"):
        soup_env.reset(INIT_STATES)


def test_bad_actions_never_reach_the_controller(soup_env: LiberoEnv) -> None:
    soup_env.reset(0)
    for action in (np.full(8, np.nan), np.zeros(7), np.array([np.inf] + [0.0] * 7)):
        with pytest.raises(ControllerError):
            soup_env.step(action)
    assert soup_env.steps == 0


def test_check_success_reports_the_goal_once_it_holds(soup_env: LiberoEnv) -> None:
    """Both cans put in the basket (the simulator's state set by the test): the env's
    own verdict turns true after they settle."""
    obs = soup_env.reset(0)
    model, data = soup_env.sim.model._model, soup_env.sim.data._data
    for obj, dx in (("alphabet_soup_1", -0.02), ("tomato_sauce_1", 0.02)):
        joint = model.joint(f"{obj}_joint0")
        data.qpos[joint.qposadr[0] : joint.qposadr[0] + 3] = obs["basket_1_pos"] + [dx, 0, 0.08]
        data.qvel[joint.dofadr[0] : joint.dofadr[0] + 6] = 0.0
    soup_env.sim.forward()
    for _ in range(40):
        soup_env.step(np.zeros(8))
    assert soup_env.check_success()


class HoldStill:
    """A policy that commands no joint motion and an open gripper."""

    name = "hold-still"

    def start(self, problem: LiberoProblem, robot: object, scene: object, percept) -> None:
        self.width = len(percept.joints) + 1

    def act(self, percept) -> np.ndarray:
        return np.r_[np.zeros(self.width - 1), -1.0]


def test_harness_scores_by_check_success_within_the_budget() -> None:
    episodes = run_suite("libero_spatial", [2], [0, 7], HoldStill)
    summary = summarise("libero_spatial", HoldStill.name, episodes)
    assert [(e.task, e.init_state, e.success, e.steps) for e in episodes] == [
        (2, 0, False, 220), (2, 7, False, 220)
    ]  # fmt: skip
    assert summary["success_rate"] == 0.0 and summary["max_steps"] == max_steps("libero_spatial")
    assert summary["interval_95"][0] == 0.0 and 0.6 < summary["interval_95"][1] < 0.7
    assert summary["tasks"]["2"]["init_states"] == [0, 7] and summary["perception"] == "env"
