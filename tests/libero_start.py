"""The start of a LIBERO episode for the libero tests: a task's env reset to a fixed
initial state and perceived, and the context the operators' legs start from (one setup,
not one per test file)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

import numpy as np

from osg_control import cli
from osg_control.control.description import RobotDescription
from osg_control.libero.drive import JointTargetDriver
from osg_control.libero.env import LiberoEnv
from osg_control.libero.executor import PlanExecutor
from osg_control.libero.legs import Context
from osg_control.libero.perception import LiberoPercept, LiberoPerception
from osg_control.libero.problem import LiberoProblem
from osg_control.libero.robot import mounted_panda


@dataclass(frozen=True)
class Start:
    """An episode's start: its problem, the mounted robot, the percept and the context."""

    problem: LiberoProblem
    robot: RobotDescription
    percept: LiberoPercept
    ctx: Context


def episode_start(suite: str, task: int, state: int = 0, settle: int = 0) -> Start:
    """``task``'s initial ``state``, perceived after ``settle`` steps holding still with
    the gripper open (the objects come to rest); the env is closed after."""
    env = LiberoEnv(suite, task)
    try:
        obs = env.reset(state)
        perception = LiberoPerception(env)
        scene, percept = perception.reset(obs, state)
        for _ in range(settle):
            percept = perception.percept(env.step(np.r_[np.zeros(7), -1.0]))
        robot = mounted_panda(env.sim)
    finally:
        env.close()
    ctx = Context.at_start(scene, JointTargetDriver(robot), robot, percept, env.problem)
    return Start(env.problem, robot, percept, ctx)


def started(
    suite: str, task: int, executor: type[PlanExecutor] = PlanExecutor
) -> tuple[PlanExecutor, LiberoPercept]:
    """``executor`` (a plan executor) started on ``task``'s initial state 0 (it plans
    there), and the percept it started from."""
    start = episode_start(suite, task)
    policy = executor()
    policy.start(start.problem, start.robot, start.ctx.scene, start.percept)
    return policy, start.percept


def scripted_episode(capsys: Any, suite: str, task: int, state: int) -> dict[str, Any]:
    """``task``'s initial ``state`` run by ``osg --domain libero evaluate benchmark`` with
    the scripted operators (its step budget, ``check_success()``): its episode log entry."""
    argv = ["--domain", "libero", "evaluate", "benchmark", "--suite", suite, "--task",
            str(task), "--init-states", f"{state}:{state + 1}", "--policy", "scripted-plan",
            "--json"]  # fmt: skip
    assert cli.main(argv) == 0
    (episode,) = json.loads(capsys.readouterr().out)["episode_log"]
    return dict(episode)
