"""Detect a MuJoCo divergence over a stretch of physics steps.

MuJoCo resets the data (time back to 0) when it meets a bad qpos/qvel/qacc, so a
divergence leaves a finite state behind: it shows in the warning counters and the clock.
``DivergenceWatch`` records both before the steps and names what happened after them;
``non_finite_state`` names a joint whose state is NaN or infinite (e.g. set from outside
between steps), which MuJoCo would answer with a reset on the next step, and which the
IK must not read.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

DIVERGENCE_WARNINGS = (
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL,
    mujoco.mjtWarning.mjWARN_BADQACC,
)
DIVERGED = "physics diverged"
"""The prefix of every divergence message (the executor stops on it instead of replanning)."""


_WARNING_SLICE = slice(int(DIVERGENCE_WARNINGS[0]), int(DIVERGENCE_WARNINGS[-1]) + 1)
"""Where the divergence warnings' tallies lie in ``data.warning.number``: one slice, so
``DivergenceWatch`` reads them as a view."""
if [int(w) for w in DIVERGENCE_WARNINGS] != list(range(_WARNING_SLICE.start, _WARNING_SLICE.stop)):
    raise ImportError("DIVERGENCE_WARNINGS must be consecutive in mujoco.mjtWarning")


class DivergenceWatch:
    """Snapshot of the warning counters and clock of ``data`` (taken at construction and
    by ``start``); ``check`` compares to it. One watch serves every control step of a data:
    the counters are a view into it, read as a slice (``warning[w].number`` one by one cost
    6 us a step, a fresh gather 3 us)."""

    def __init__(self, data: mujoco.MjData) -> None:
        self.data = data
        self._counters = data.warning.number[_WARNING_SLICE]
        self.start()

    def start(self) -> None:
        """Take the snapshot now (before a stretch of steps)."""
        self.time = float(self.data.time)
        self.counts = self._counters.tolist()

    def check(self) -> str | None:
        """The divergence since the snapshot, as a message starting ``DIVERGED``; else None."""
        now = self._counters.tolist()
        if now != self.counts:
            for warning, after, before in zip(DIVERGENCE_WARNINGS, now, self.counts, strict=True):
                if after > before:
                    return f"{DIVERGED}: MuJoCo reported {warning.name} and reset the state"
        if self.data.time < self.time:
            return f"{DIVERGED}: MuJoCo reset the state"
        return non_finite_state(self.data)


def non_finite_state(data: mujoco.MjData, fields: tuple[str, ...] = ("qpos", "qvel")) -> str | None:
    """A message starting ``DIVERGED`` naming the first joint with a NaN or infinite value
    in ``fields`` (``"qpos"``, ``"qvel"``); None when they are finite."""
    model = data.model
    for name in fields:
        values = getattr(data, name)
        # The fast path: a finite sum of squares means finite values (an overflow to inf,
        # values beyond 1e154, falls through to the search, which then finds nothing).
        if math.isfinite(values @ values):
            continue
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            index = int(bad[0])
            if name == "qpos":
                joint = int(np.searchsorted(model.jnt_qposadr, index, side="right")) - 1
            else:
                joint = int(model.dof_jntid[index])
            return (
                f"{DIVERGED}: non-finite {name} of joint {model.joint(joint).name!r} "
                f"({values[index]})"
            )
    return None


def is_divergence(failure: str | None) -> bool:
    """Whether a failure message reports a divergence (anywhere in a chained message)."""
    return failure is not None and DIVERGED in failure
