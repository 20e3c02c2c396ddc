"""Fast Downward as a planning backend: the driver shipped inside ``up-fast-downward``.

The package's Python module needs ``unified_planning``, so it is never imported: the driver
script is located on disk and run in a subprocess with an optimal configuration
(``seq-opt-lmcut``: A* with the admissible LM-cut heuristic).
"""

from __future__ import annotations

import importlib.util
import math
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from osg_control.errors import PlanningError
from osg_control.planning.task import (
    NO_LIMITS,
    PlanResult,
    SearchLimits,
    SearchStats,
    Task,
    no_plan,
    plan_result,
    unknown,
)

ALIAS = "seq-opt-lmcut"
UNSOLVABLE_EXIT_CODES = frozenset({10, 11})
"""The driver's exit codes for "proved unsolvable" by the translator or the search."""
LIMIT_EXIT_CODES = {
    12: "search incomplete",
    22: "memory limit",
    23: "time limit",
    24: "time and memory limits",
}
"""The driver's exit codes for "stopped without an answer", and what stopped it."""
_GRACE_S = 30.0
"""Seconds the subprocess gets beyond the driver's own time limit before it is killed."""
_EXPANDED = re.compile(r"\] Expanded (\d+) state", re.MULTILINE)
_GENERATED = re.compile(r"\] Generated (\d+) state", re.MULTILINE)


def find_fast_downward() -> Path | None:
    """The ``fast-downward.py`` driver inside the installed ``up_fast_downward``, or None."""
    spec = importlib.util.find_spec("up_fast_downward")
    for root in (spec.submodule_search_locations or []) if spec else []:
        driver = Path(root) / "downward" / "fast-downward.py"
        if driver.is_file():
            return driver
    return None


def _first_int(pattern: re.Pattern[str], text: str) -> int:
    match = pattern.search(text)
    return int(match.group(1)) if match else 0


def _read_plan(path: Path) -> list[str]:
    """Operator names from a ``sas_plan`` file: ``(move a b)`` lines, ``;`` comments."""
    lines = (line.strip() for line in path.read_text().splitlines())
    return [" ".join(line[1:-1].split()) for line in lines if line.startswith("(")]


def run_fast_downward(
    task: Task, domain_file: Path, problem_file: Path, limits: SearchLimits = NO_LIMITS
) -> PlanResult:
    """Plan with Fast Downward on PDDL files; report the plan in terms of ``task``.

    ``task`` must be the grounding of the same files: it supplies each step's cost, checks
    the plan, and names the unreached goal facts when Fast Downward proves there is no plan.

    Args:
        task: the ground task of the files.
        domain_file: the PDDL domain.
        problem_file: the PDDL problem.
        limits: ``time_s`` becomes the driver's ``--overall-time-limit`` (``max_states``
            concerns the built-in search only).

    Returns:
        The plan (stats: states Fast Downward expanded and generated, wall time including
        its translator and process start), a "no plan" result when Fast Downward proves
        there is none, or "unknown" when it stopped at a limit.

    Raises:
        PlanningError: the driver is missing, fails, or returns a plan that does not solve
            ``task``.
    """
    driver = find_fast_downward()
    if driver is None:
        raise PlanningError(
            "Fast Downward not found: the package up-fast-downward (with its "
            "downward/fast-downward.py driver) is not installed"
        )
    with tempfile.TemporaryDirectory(prefix="osg-fd-") as tmp:
        plan_file = Path(tmp) / "sas_plan"
        command = [
            sys.executable,
            str(driver),
            "--plan-file",
            str(plan_file),
            *(["--overall-time-limit", f"{math.ceil(limits.time_s)}s"] if limits.time_s else []),
            "--alias",
            ALIAS,
            str(Path(domain_file).resolve()),
            str(Path(problem_file).resolve()),
        ]
        start = time.perf_counter()
        timeout = limits.time_s + _GRACE_S if limits.time_s else None
        try:
            done = subprocess.run(
                command, cwd=tmp, capture_output=True, text=True, timeout=timeout, check=False
            )
        except subprocess.TimeoutExpired:
            stats = SearchStats(0, 0, time.perf_counter() - start)
            return unknown("fast-downward", task, stats, f"time limit {limits.time_s:g} s")
        stats = SearchStats(
            expanded=_first_int(_EXPANDED, done.stdout),
            generated=_first_int(_GENERATED, done.stdout),
            time_s=time.perf_counter() - start,
        )
        if done.returncode in UNSOLVABLE_EXIT_CODES:
            return no_plan("fast-downward", task, stats)
        if done.returncode in LIMIT_EXIT_CODES:
            return unknown("fast-downward", task, stats, LIMIT_EXIT_CODES[done.returncode])
        if done.returncode != 0 or not plan_file.is_file():
            tail = "\n".join((done.stdout + done.stderr).strip().splitlines()[-8:])
            raise PlanningError(f"Fast Downward failed (exit code {done.returncode}):\n{tail}")
        names = _read_plan(plan_file)
    by_lower = {op.name.lower(): op.name for op in task.operators}
    return plan_result("fast-downward", task, [by_lower.get(n, n) for n in names], stats)
