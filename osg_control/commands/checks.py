"""Up-front checks of parsed ``osg`` arguments: a value outside its domain is refused before
any work starts, with a ``UsageError`` naming the option (exit code 2).

The checks are keyed by the argument's destination name, so every verb that takes e.g.
``--episodes`` gets the same rule; ``cli.main`` calls ``check_args`` once after parsing.
Every numeric option has both bounds (``CHECKS``; docs/reliability.md lists them): a value
past what the libraries underneath take (torch threads, HDF5's 64-bit seed attribute,
Fast Downward's time limit) is refused here rather than crashing hours into a run.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from osg_control.errors import PlanningError, UsageError
from osg_control.execution import MAX_REPLANS
from osg_control.perception.spec import MAX_NOISE
from osg_control.planning.task import MAX_STATES, MAX_TIME_S
from osg_control.seeding import MAX_SEED

if TYPE_CHECKING:
    from osg_control.domain.base import Domain


def _option(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def _whole(low: int, high: int) -> Callable[[str, Any], None]:
    """A whole-number option in [low, high]."""

    def check(dest: str, value: Any) -> None:
        for item in value if isinstance(value, list) else [value]:
            if item < low:
                raise UsageError(f"{_option(dest)} must be >= {low}, got {item}")
            if item > high:
                raise UsageError(f"{_option(dest)} must be <= {high:,}, got {_shown(item)}")

    return check


def _shown(value: Any) -> str:
    text = str(value)
    return text if len(text) <= 30 else f"{text[:12]}...({len(text)} digits)"


def _finite_range(
    low: float, high: float, low_open: bool = False, high_open: bool = False
) -> Callable[[str, Any], None]:
    def check(dest: str, value: Any) -> None:
        for item in value if isinstance(value, list) else [value]:
            above = item > low if low_open else item >= low
            below = item < high if high_open else item <= high
            if not (math.isfinite(item) and above and below):
                left = "(" if low_open else "["
                right = ")" if high_open else "]"
                raise UsageError(
                    f"{_option(dest)} must lie in {left}{low:g}, {high:g}{right}, got {item}"
                )

    return check


def _goal(dest: str, value: Any) -> None:
    if not str(value).split():
        raise UsageError(f"{_option(dest)} needs at least one world fact, got {value!r}")


def _video(dest: str, value: Any) -> None:
    """``--video`` needs an OpenGL back end (MUJOCO_GL=egl or osmesa on a headless machine)."""
    _needs_gl(_option(dest), "leave out --video")


def _perception(dest: str, value: Any) -> None:
    """``--perception camera`` renders images: it needs an OpenGL back end too."""
    if value == "camera":
        _needs_gl(f"{_option(dest)} camera", "choose another perception")


def _needs_gl(what: str, otherwise: str) -> None:
    """Render a tiny scene once, in a child process: a GL context made in this process
    would be inherited by the forked workers of ``--workers N``, whose own renderers then
    hang (EGL does not survive a fork).

    Raises:
        UsageError: no OpenGL back end, naming ``MUJOCO_GL`` (exit 2, nothing run).
    """
    import subprocess
    import sys

    try:
        probe = subprocess.run(
            [sys.executable, "-c", _GL_PROBE],
            check=False,
            capture_output=True,
            text=True,
            timeout=120,
        )
        failure = None if probe.returncode == 0 else (probe.stderr.strip() or "no output")
    except (OSError, subprocess.TimeoutExpired) as err:
        failure = str(err)
    if failure is not None:
        reason = failure.splitlines()[-1]
        raise UsageError(
            f"{what}: no OpenGL back end to render with ({reason}); set MUJOCO_GL=egl "
            f"or MUJOCO_GL=osmesa, or {otherwise}"
        )


_GL_PROBE = """
import warnings
import mujoco
warnings.simplefilter("error")  # GLFW reports a missing display as a warning
model = mujoco.MjModel.from_xml_string("<mujoco><worldbody/></mujoco>")
renderer = mujoco.Renderer(model, 16, 16)
renderer.update_scene(mujoco.MjData(model))
renderer.render()
renderer.close()
"""
"""The render ``_needs_gl`` runs in a child process (any failure: no back end)."""


MAX_COUNT = 10**9
"""The most episodes, training steps or checks a command takes (a billion episodes already
run in flat memory; more would not finish)."""
MAX_PARALLEL = 1024
"""The most worker processes or torch threads (torch segfaults at 100,000 threads)."""
CHECKS: dict[str, Callable[[str, Any], None]] = {
    "goal": _goal,
    "episodes": _whole(1, MAX_COUNT),
    "steps": _whole(1, MAX_COUNT),
    "check_every": _whole(1, MAX_COUNT),
    "check_episodes": _whole(1, MAX_COUNT),
    "patience": _whole(1, MAX_COUNT),
    "epochs": _whole(1, 10**6),
    "batch_size": _whole(1, 2**20),
    "threads": _whole(1, MAX_PARALLEL),
    "workers": _whole(1, MAX_PARALLEL),
    "seed": _whole(0, MAX_SEED),
    "replans": _whole(0, MAX_REPLANS),
    "max_replans": _whole(0, MAX_REPLANS),
    "max_states": _whole(1, MAX_STATES),
    "noise": _finite_range(0.0, MAX_NOISE),
    "object_noise": _finite_range(0.0, MAX_NOISE),
    "obs_noise": _finite_range(0.0, MAX_NOISE),
    "time_limit": _finite_range(0.0, MAX_TIME_S, low_open=True),
    "filter": _finite_range(0.0, 1.0, low_open=True),
    "validation_fraction": _finite_range(0.0, 1.0, high_open=True),
    "video": _video,
    "perception": _perception,
}
"""Argument destination -> its check (run only when the argument is present and not None).
Every numeric option of every verb has an entry with both bounds
(``tests/test_reliability_bounds.py`` walks the parser to hold that)."""


def _domain_values(args: argparse.Namespace) -> None:
    """``--domain`` names a registered domain; ``--start`` one of its nodes (or random);
    ``--facts`` and ``--goal`` its facts (an ``(at NODE)`` goal atom is left to the planner)."""
    from osg_control.domain.registry import get_domain
    from osg_control.errors import DomainError

    if getattr(args, "command", None) in (None, "domains"):
        return
    try:
        domain = get_domain(args.domain)
    except DomainError as err:
        raise UsageError(f"--domain: {err}") from None
    _robot(args, domain)
    start = getattr(args, "start", None)
    if start is not None and start != "random" and start not in domain.nodes:
        raise UsageError(
            f"--start: unknown start {start!r} in domain {domain.name!r}; use 'random' or one "
            f"of {list(domain.nodes)}"
        )
    for dest in ("facts", "goal"):
        value = getattr(args, dest, None)
        if value is None or (dest == "goal" and getattr(args, "files", None)):
            continue
        try:
            fact_atoms(domain, value, goal=dest == "goal")
        except PlanningError as err:
            raise UsageError(f"{_option(dest)}: {err} (domain {domain.name!r})") from None
    if getattr(args, "randomize_objects", False) and not domain.objects:
        raise UsageError(
            f"--randomize-objects: domain {domain.name!r} has no object with a placement "
            "region (its Domain.objects is empty), so there is nothing to place"
        )
    _models(args, domain)


def fact_atoms(domain: Domain, text: str, goal: bool = False) -> list[str]:
    """Facts written on the command line (``door-open``, ``(door-open)``, ``(in-cabinet
    cube-1)``; a goal may also name one ``(at NODE)``) as the domain's fact names.

    Raises:
        PlanningError: an unreadable atom, an unknown predicate, object or node, a wrong
            arity, or ``(at NODE)`` outside a goal.
    """
    from osg_control.domain.lifted import AT
    from osg_control.planning.pddl_io import parse_atoms

    facts = []
    for atom in parse_atoms(text):
        if atom[0] == AT and len(atom) == 2:
            if not goal:
                raise PlanningError(f"(at {atom[1]}) is not a world fact; use --from-node")
            domain.lifting.check_atom(atom)
            facts.append(f"(at {atom[1]})")
            continue
        facts.append(domain.lifting.ground_fact("(" + " ".join(atom) + ")"))
    return facts


def _robot(args: argparse.Namespace, domain: Domain) -> None:
    """``--robot`` is a robot the domain's env can drive, whose description matches its
    models (workers, Ray's included, rebuild it from ``Domain.ref``).

    Raises:
        UsageError: the domain drives its own arm.
        RobotDescriptionError: the robot's description does not match its models (exit 1).
    """
    robot = getattr(args, "robot", None)
    if robot is None or robot == domain.robot:
        return
    if domain.robot is None:
        raise UsageError(
            f"--robot: domain {domain.name!r} drives its own arm; no robot can be chosen"
        )
    from osg_control.robots.registry import get_robot

    get_robot(robot)


def _models(args: argparse.Namespace, domain: Domain) -> None:
    """``--models DIR`` holds a checkpoint of every skill the command will run: DIR itself
    for ``eval-skills`` (its ``--skill`` list), DIR's ``skills/`` for the verbs taking a
    defaults folder.

    Raises:
        CheckpointError: naming the folder and every missing skill (exit 1: a file error).
    """
    from osg_control.learning.checkpoints import require_skills

    models = getattr(args, "models", None)
    if models is None:
        return
    if args.command == "eval-skills":
        wanted = args.skill or list(domain.skills_by_name)
        require_skills(models, [name for name in wanted if name in domain.skills_by_name])
    else:
        require_skills(models / "skills", list(domain.skills_by_name))


def check_args(args: argparse.Namespace, domain_values: bool = True) -> None:
    """Run every applicable check on parsed arguments.

    Args:
        args: the parsed arguments.
        domain_values: also check the values that name a ``Domain``'s things (off for a
            domain that brings its own verbs, which check their own values).

    Raises:
        UsageError: the first value out of its domain, naming the option.
    """
    for dest, check in CHECKS.items():
        value = getattr(args, dest, None)
        if value is not None:
            check(dest, value)
    if domain_values:
        _domain_values(args)
