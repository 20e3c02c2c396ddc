"""The adapter's reset helpers: set-ups (a skill's start world made by scripts through the
env's own steps) and the drive to a start pose.

Both prepare an episode's start; they are not the episode. They run on the simulator's
truth (the true state for the set-up scripts, the true TCP for the drive): an evaluation's
perception and its noise are the episode's, not theirs.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from osg_control.domain.spec import ScriptParams
from osg_control.environment.actions import scale_into
from osg_control.environment.success import GRIPPER_CLOSED_CMD, GRIPPER_OPEN_CMD, effects_hold
from osg_control.errors import SimulationError

NOISE_FREE = ScriptParams(threshold_std=0.0, noise_std=0.0)
"""Algorithm 1 without its noise: a set-up's first attempt."""
SETUP_ATTEMPTS = 5
"""How often ``reset`` retries a skill's set-up (a noisy script) before giving up."""


def set_up(adapter: Any, node: str, seed: int | None) -> None:
    """Bring the env from its reset to ``node`` in the world a skill starting there needs,
    by running the node's set-up skills' scripts (``adapter.setups``) through the env's own
    steps: first noise-free, then, if a skill's effects do not hold at its end, with the
    scripts' own Algorithm 1 noise from a new reset, up to ``SETUP_ATTEMPTS`` attempts.

    Raises:
        SimulationError: no attempt gave every set-up skill its effects.
    """
    from osg_control.data.scripted import ScriptedPolicy

    chain = adapter.setups[node]
    with adapter.outside_the_skill():
        for attempt in range(SETUP_ATTEMPTS):
            if attempt:
                adapter.reset_env(seed)
            done = True
            for setup in chain:
                params = None if attempt else NOISE_FREE
                policy = ScriptedPolicy(setup, adapter.script_rng, params, adapter.action_bounds)
                policy.reset()
                while not policy.done and not adapter.skill_success(setup):
                    # The true state: the set-up prepares the scene, it is not the
                    # evaluated episode (whose perception and noise it must not see).
                    adapter.step(policy(adapter.true_state()))
                if not effects_hold(setup, adapter.facts()):
                    done = False
                    break
            if done:
                return
        raise SimulationError(
            f"set-up {[s.name for s in chain]} of node {node!r} did not give its effects "
            f"in {SETUP_ATTEMPTS} attempts"
        )


def drive_to(
    adapter: Any,
    position: np.ndarray,
    rotation: np.ndarray,
    gripper: str,
    max_steps: int = 40,
    tolerance: float = 0.01,
) -> int:
    """Step toward a TCP pose (position, rotation matrix) with the gripper ``"open"`` or
    ``"closed"``, on the true TCP; return the steps used."""
    from osg_control.control.ik import rotation_error

    bounds = adapter.action_bounds
    g = GRIPPER_OPEN_CMD if gripper == "open" else GRIPPER_CLOSED_CMD
    for step in range(max_steps):
        pos, rot = adapter.tcp_pose()
        error = np.asarray(position) - pos
        turn = rotation_error(rot, rotation)
        if np.linalg.norm(error) < tolerance and np.linalg.norm(turn) < 0.05:
            return step
        action = np.concatenate(
            [scale_into(error, bounds[0]), scale_into(turn, bounds[3]), [g]]
        )
        *_, terminated, truncated, _info = adapter.step(action)
        if terminated or truncated:
            return step + 1
    return max_steps
