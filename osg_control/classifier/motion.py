"""The classifier's motion input: the arm's last TCP command and a decaying memory of them.

A state on the way between two nodes reads the same whichever way the arm travels, so the
state alone cannot tell a skill from its reverse (Table II's main confusion). The robot
knows what it commanded: the classifier also reads the previous control step's TCP motion
command (the action's first six entries) and an exponential average of the commands
(``MOTION_DECAY`` per control step), which keeps the direction of travel when a policy
slows into its termination pose. Both are zero at rest: at an episode's start, and decaying
through steps without TCP motion (a joint reset, opening the gripper).

The same rule builds the training inputs from a data set's recorded actions
(``motion_features``) and the run-time input from the executor's commands
(``MotionMemory``).
"""

from __future__ import annotations

import numpy as np

MOTION_DIM = 6
"""TCP motion entries of an action: translation [m] and rotation [rad] per step."""
MOTION_DECAY = 0.9
"""Per-control-step decay of the motion memory (a time constant of 0.5 s at 20 Hz)."""
MOTION_FEATURES = 2 * MOTION_DIM
"""The previous command and the memory."""


def motion_features(actions: np.ndarray, episode_starts: np.ndarray) -> np.ndarray:
    """Each step's motion input (N, ``MOTION_FEATURES``) from a data set's actions (N, 7):
    the previous step's TCP command and the memory of the commands before the step, both
    zero at an episode's first step (``episode_starts``: indices of those steps)."""
    commands = np.asarray(actions, dtype=np.float64)[:, :MOTION_DIM]
    previous = np.zeros_like(commands)
    previous[1:] = commands[:-1]
    starts = np.zeros(len(commands), dtype=bool)
    starts[np.asarray(episode_starts, dtype=np.int64)] = True
    previous[starts] = 0.0
    memory = np.zeros_like(commands)
    current = np.zeros(MOTION_DIM)
    for index in range(len(commands)):
        current = np.zeros(MOTION_DIM) if starts[index] else _decayed(current, previous[index])
        memory[index] = current
    return np.concatenate([previous, memory], axis=1).astype(np.float32)


def _decayed(memory: np.ndarray, command: np.ndarray) -> np.ndarray:
    """The memory after one more control step that commanded ``command``."""
    return MOTION_DECAY * memory + (1.0 - MOTION_DECAY) * command


class MotionMemory:
    """The run-time motion input: fed every control step's command, read before a choice."""

    def __init__(self) -> None:
        self._previous = np.zeros(MOTION_DIM)
        self._memory = np.zeros(MOTION_DIM)

    def commanded(self, action: np.ndarray) -> None:
        """Record a control step that sent ``action`` (its TCP motion entries)."""
        self._previous = np.asarray(action, dtype=np.float64)[:MOTION_DIM].copy()
        self._memory = _decayed(self._memory, self._previous)

    def still(self, steps: int) -> None:
        """Record ``steps`` control steps without TCP motion (joint reset, gripper)."""
        for _ in range(steps):
            self.commanded(np.zeros(MOTION_DIM))

    def features(self) -> np.ndarray:
        """The input for the next choice: (``MOTION_FEATURES``,)."""
        return np.concatenate([self._previous, self._memory])
