"""LIBERO's suites, their published step budgets and initial-state counts, declared once.

The base suites are LIBERO's four; LIBERO-PRO perturbs each as ``<base>_<variant>``:
``swap`` (pairs of objects exchange their initial regions), ``object`` (object assets
replaced), ``task`` (a new goal in the same scene). Its ``_lan`` variant (a paraphrased
instruction) is left out: goals here are read from the task file, not the instruction, so
it is the base suite again. A variant inherits its base suite's step budget.
"""

from __future__ import annotations

from osg_control.errors import UsageError, lookup

STEP_BUDGETS: dict[str, int] = {
    "libero_10": 520,
    "libero_goal": 300,
    "libero_object": 280,
    "libero_spatial": 220,
}
"""Base suite -> the step budget of an episode in the published evaluations (20 Hz control)."""

PRO_VARIANTS: tuple[str, ...] = ("swap", "object", "task")
"""LIBERO-PRO's perturbations run here (``<base>_<variant>``)."""

INIT_STATES = 50
"""Fixed initial states each task ships (``<task>.pruned_init``): an episode is one of them."""


def suite_names() -> tuple[str, ...]:
    """Every suite the domain runs: the four base suites, then their LIBERO-PRO variants."""
    return (*STEP_BUDGETS, *(f"{b}_{v}" for b in STEP_BUDGETS for v in PRO_VARIANTS))


def base_suite(suite: str) -> str:
    """The LIBERO suite a suite name perturbs (itself for a base suite).

    Raises:
        UsageError: an unknown suite, listing the known ones (exit 2).
    """
    lookup(dict.fromkeys(suite_names()), suite, "suite", lambda m: UsageError(f"--suite: {m}"))
    for base in STEP_BUDGETS:
        if suite == base or suite.startswith(f"{base}_"):
            return base
    raise AssertionError(suite)  # every name of suite_names() starts with its base


def max_steps(suite: str) -> int:
    """The suite's published step budget per episode (its base suite's)."""
    return STEP_BUDGETS[base_suite(suite)]


def parse_init_states(text: str) -> range:
    """``A:B`` -> the initial states ``A .. B-1`` (Python's half-open slice), within
    ``0 .. INIT_STATES-1``.

    Raises:
        UsageError: not ``A:B`` of whole numbers, empty, or outside 0-49 (exit 2).
    """
    try:
        start_text, stop_text = text.split(":")
        start, stop = int(start_text), int(stop_text)
    except ValueError:
        raise UsageError(f"--init-states must be A:B (whole numbers), got {text!r}") from None
    if not (0 <= start < stop <= INIT_STATES):
        raise UsageError(
            f"--init-states {text!r} is outside the {INIT_STATES} initial states: need "
            f"0 <= A < B <= {INIT_STATES} (states A .. B-1)"
        )
    return range(start, stop)
