"""Detect a MuJoCo divergence over a stretch of physics steps.

MuJoCo resets the data (time back to 0) when it meets a bad qpos/qvel/qacc, so a
divergence leaves a finite state behind: it shows in the warning counters and the clock.
``DivergenceWatch`` records both before the steps and names what happened after them.
"""

from __future__ import annotations

import mujoco
import numpy as np

DIVERGENCE_WARNINGS = (
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL,
    mujoco.mjtWarning.mjWARN_BADQACC,
)
DIVERGED = "physics diverged"
"""The prefix of every divergence message (the executor stops on it instead of replanning)."""


class DivergenceWatch:
    """Snapshot of the warning counters and clock of ``data``; ``check`` compares to it."""

    def __init__(self, data: mujoco.MjData) -> None:
        self.data = data
        self.time = float(data.time)
        self.counts = [int(data.warning[w].number) for w in DIVERGENCE_WARNINGS]

    def check(self) -> str | None:
        """The divergence since the snapshot, as a message starting ``DIVERGED``; else None."""
        for warning, count in zip(DIVERGENCE_WARNINGS, self.counts, strict=True):
            if int(self.data.warning[warning].number) > count:
                return f"{DIVERGED}: MuJoCo reported {warning.name} and reset the state"
        if self.data.time < self.time:
            return f"{DIVERGED}: MuJoCo reset the state"
        if not (np.all(np.isfinite(self.data.qpos)) and np.all(np.isfinite(self.data.qvel))):
            return f"{DIVERGED}: non-finite joint state"
        return None


def is_divergence(failure: str | None) -> bool:
    """Whether a failure message reports a divergence (anywhere in a chained message)."""
    return failure is not None and DIVERGED in failure
