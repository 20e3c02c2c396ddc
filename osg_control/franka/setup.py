"""The adapter's multi-step motions: the reset's options, set-ups (a skill's start world
made by scripts through the env's own steps), the drive to a start pose, and the joint
reset between skills.

Set-ups and the drive prepare an episode's start; they are not the episode. They run on
the simulator's truth (the true state for the set-up scripts, the true TCP for the drive):
an evaluation's perception and its noise are the episode's, not theirs. The joint reset is
part of the episode: it reads the perceived joints (``FrankaKitchenAdapter._controlled``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from osg_control.control.robot_model import workspace
from osg_control.domain.spec import Node, ScriptParams
from osg_control.environment.actions import scale_into
from osg_control.environment.options import (
    GRIPPER_STATES,
    Bounds,
    check_names,
    check_reach,
    check_start_options,
    choice_option,
    facts_option,
    node_option,
    reset_options,
)
from osg_control.environment.success import GRIPPER_CLOSED_CMD, GRIPPER_OPEN_CMD, effects_hold
from osg_control.errors import EnvOptionError, SimulationError

RESET_OPTIONS = ("node", "position", "radius", "angle", "max_steps", "gripper", "facts")
"""The options ``FrankaKitchenAdapter.reset`` knows; any other name is refused."""
DRIVE_STEPS = Bounds(integer=True)
"""The range of the ``max_steps`` reset option (an integer >= 0)."""

NOISE_FREE = ScriptParams(threshold_std=0.0, noise_std=0.0)
"""Algorithm 1 without its noise: a set-up's first attempt."""
SETUP_ATTEMPTS = 5
"""How often ``reset`` retries a skill's set-up (a noisy script) before giving up."""


@dataclass(frozen=True)
class Start:
    """The reset's options, checked: where the drive goes (``node_name`` None: no drive)."""

    node_name: str | None
    node: Node
    centre: np.ndarray
    radius: float
    angle: float
    max_steps: int
    gripper: str
    facts: frozenset[str]


def start_options(adapter: Any, options: dict[str, Any] | None) -> Start:
    """Check the reset options (see ``FrankaKitchenAdapter.reset``) before anything runs.

    Raises:
        EnvOptionError: an unknown option name (the known ones listed), a value out of its
            domain, or a ``gripper`` the start does not have.
    """
    options = reset_options(options)
    check_names(options, RESET_OPTIONS, "reset option")
    skill = adapter.skill
    node_name = options.get("node")
    if node_name is not None:
        node_option(options, adapter.home, adapter.nodes)  # refuses "" and unknown names
    else:
        node_name = skill.start if skill else None
    if node_name is None and "position" in options:
        node_name = adapter.home
    node = adapter.nodes[node_name or adapter.home]
    centre, radius, angle = check_start_options(
        options.get("position", node.position),
        options.get("radius", 0.0),
        options.get("angle", 0.0),
    )
    if "position" in options:
        check_reach("position", centre, workspace(adapter.robot))
    max_steps = options.get("max_steps", 40)
    if not DRIVE_STEPS.admits(max_steps):
        raise EnvOptionError(
            f"reset option max_steps must be {DRIVE_STEPS.describe()}, got {max_steps!r}"
        )
    start_gripper = node.gripper if node_name is not None else "open"
    gripper = choice_option("gripper", options.get("gripper", start_gripper), GRIPPER_STATES)
    asked = options.get("facts")
    facts = frozenset() if asked is None else facts_option(asked, adapter.world_facts)
    if gripper != start_gripper:
        raise EnvOptionError(
            f"reset options contradict each other: gripper {gripper!r}, but the start "
            f"{node_name or 'of the env'} has the gripper {start_gripper}"
        )
    return Start(node_name, node, centre, radius, angle, max_steps, gripper, facts)


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
                policy = ScriptedPolicy(
                    setup, adapter.script_rng, params, bounds=adapter.action_bounds
                )
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
    from osg_control.control.rotations import rotation_error

    bounds = adapter.action_bounds
    g = GRIPPER_OPEN_CMD if gripper == "open" else GRIPPER_CLOSED_CMD
    for step in range(max_steps):
        pos, rot = adapter.tcp_pose()
        error = np.asarray(position) - pos
        turn = rotation_error(rot, rotation)
        if np.linalg.norm(error) < tolerance and np.linalg.norm(turn) < 0.05:
            return step
        action = np.concatenate([scale_into(error, bounds[0]), scale_into(turn, bounds[3]), [g]])
        *_, terminated, truncated, _info = adapter.step(action)
        if terminated or truncated:
            return step + 1
    return max_steps


def joint_reset(adapter: Any, max_steps: int, tolerance: float) -> int:
    """Drive the perceived joints toward the env's reset posture while the perceived TCP
    holds its pose (``adapter.reset_ik``: a strong posture task under the frame task),
    through the adapter's steps; stop when within ``tolerance`` [rad] or no longer
    improving; the steps used.

    Raises:
        SimulationError: the physics diverged.
    """
    from osg_control.control.divergence import non_finite_state
    from osg_control.environment.joint_reset import drive_to_posture

    _q, pos, rot, _bias = adapter._controlled()

    def step(q: np.ndarray) -> bool:
        action = None
        if non_finite_state(adapter.data, ("qpos",)) is None:
            bias = adapter._controlled()[3]
            velocity = adapter.reset_ik.solve_velocity(q, pos, rot)
            action = adapter.arm_action(velocity, bias)
        *_, terminated, truncated, info = adapter.advance(action, np.zeros(7))
        if "failure" in info:
            raise SimulationError(f"joint reset: {info['failure']}")
        return bool(terminated or truncated)

    return drive_to_posture(
        lambda: adapter._controlled()[0], adapter.posture, step, max_steps, tolerance
    )
