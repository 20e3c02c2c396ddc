"""A suite's tasks as LIBERO's package ships them: task files, fixed initial states."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Sequence
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from osg_control.errors import UsageError
from osg_control.libero.extra import require_libero
from osg_control.libero.problem import LiberoProblem, read_problem
from osg_control.libero.suites import INIT_STATES, base_suite


@cache
def _suite(suite: str) -> Any:
    """LIBERO's benchmark object of a suite (checked against ``suite_names`` first). What
    LIBERO prints while making it goes to stderr: stdout is the commands' (``--json``)."""
    base_suite(suite)
    benchmark = require_libero("libero.libero.benchmark")
    with contextlib.redirect_stdout(sys.stderr):
        return benchmark.get_benchmark_dict()[suite]()


def task_count(suite: str) -> int:
    """The number of tasks of a suite."""
    return int(_suite(suite).n_tasks)


def check_task_indices(suite: str, indices: Sequence[int] | None) -> tuple[int, ...]:
    """The task indices asked for (all of the suite's when None).

    Raises:
        UsageError: an index outside the suite (exit 2), naming it and the range.
    """
    count = task_count(suite)
    if indices is None:
        return tuple(range(count))
    bad = [i for i in indices if not 0 <= i < count]
    if bad or not indices:
        raise UsageError(f"--task: {suite} has tasks 0-{count - 1}; got {bad or 'none'}")
    return tuple(dict.fromkeys(indices))


def task_file(suite: str, index: int) -> Path:
    """The task's BDDL file."""
    return Path(_suite(suite).get_task_bddl_file_path(index))


def task_name(suite: str, index: int) -> str:
    """The task's name (its task file's stem)."""
    return str(_suite(suite).get_task(index).name)


def task_problem(suite: str, index: int) -> LiberoProblem:
    """The task's file as a typed problem."""
    return read_problem(task_file(suite, index), suite, index)


def init_states(suite: str, index: int) -> np.ndarray:
    """The task's fixed initial states, ``(INIT_STATES, n)`` flattened MuJoCo states
    ``[time, qpos, qvel]``.

    Raises:
        RuntimeError: the package ships another number of them (a broken install).
    """
    states = np.asarray(_suite(suite).get_task_init_states(index), dtype=float)
    if states.ndim != 2 or states.shape[0] != INIT_STATES:
        raise RuntimeError(
            f"{suite} task {index}: expected {INIT_STATES} initial states, the package has "
            f"{states.shape}"
        )
    return states
