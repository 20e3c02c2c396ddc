"""LIBERO's env as the package ships it, state only: a task's scene, reset to one of its
fixed initial states, stepped by its own controller, scored by its own ``check_success()``.

Options (``ENV_OPTIONS``): no renderer and no cameras (``has_offscreen_renderer=False,
use_camera_obs=False``: no GL needed, about 200 ms a step saved), and ``hard_reset=False``
(a reset reuses the compiled model: 0.06 s instead of several). The arm's controller is
robosuite's ``JOINT_POSITION`` (joint deltas, ``CONTROLLER``), which our IK drives.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from osg_control.errors import ControllerError, UsageError
from osg_control.libero.extra import require_libero
from osg_control.libero.problem import LiberoProblem
from osg_control.libero.suites import INIT_STATES
from osg_control.libero.tasks import init_states, task_file, task_problem
from osg_control.robots.panda import PANDA

ENV_OPTIONS: dict[str, Any] = {
    "has_renderer": False,
    "has_offscreen_renderer": False,
    "use_camera_obs": False,
    "hard_reset": False,
}
CONTROLLER = "JOINT_POSITION"
"""robosuite's controller the arm is driven through: the action is 7 joint deltas divided
by ``JOINT_DELTA_LIMIT`` (so in [-1, 1]) and the gripper command in [-1, 1] (1 closes)."""
CONTROL_HZ = 20.0
"""LIBERO's control rate [Hz] (``ControlEnv``'s ``control_freq``): one action a step."""
JOINT_KP = 300.0
"""The JOINT_POSITION controller's stiffness (its config's ``kp``, critically damped as
robosuite's): the top of robosuite's own kp range (its default 50 lets the arm cover only a
small part of a commanded step: a 20 cm reach took 38-54 steps at 50, 17-24 at 300;
docs/libero.md). The controller is the agent's side of the benchmark; the env, its states
and its scoring are untouched."""
JOINT_DELTA_LIMIT = max(PANDA.arm.velocity) / CONTROL_HZ
"""The JOINT_POSITION scale (its config's ``output_max``): an action of 1 is a joint delta of
this [rad], the Panda's fastest joint's speed limit over one step (0.13 rad). robosuite's
default 0.05 capped every joint near 1 rad/s, and the arm, which covers about 0.43 of a
commanded delta a step at ``JOINT_KP`` (``sqrt(kp) / 2`` of it a second), crawled at 0.36
rad/s: the 220 steps of LIBERO-Spatial ran out in every failed episode. The IK caps each
joint at its own limit (``drive.JointTargetDriver``)."""


def episode_seeds(seed: int, init_state: int) -> tuple[int, int]:
    """The two seeds of one episode, from the run's ``seed`` and the initial state: LIBERO's
    fixture placement at reset (``LiberoEnv.reset``), then the fixture sensor's noise
    (``perception.FixtureSensor``). Neither depends on the task or on which episodes ran
    before, so a run's episodes are the same whatever worker runs them."""
    first, second = np.random.SeedSequence([seed, init_state]).generate_state(2)
    return int(first), int(second)


def _reset_grippers(gripper: Any) -> None:
    """Zero a robot's gripper command state, as a freshly built model has it.

    robosuite's grippers keep the position they are commanded to (``current_action``,
    ramped each step toward the command's sign) on the model object. ``hard_reset=False``
    never rebuilds the model, so without this an episode's gripper starts from the previous
    episode's last command: the same initial state gave different trajectories depending on
    which episode ran before it in a worker (the fingers 1 cm apart after the first step).
    """
    for one in gripper.values() if isinstance(gripper, dict) else (gripper,):
        one.current_action = np.zeros(one.dof)


class LiberoEnv:
    """One LIBERO task's env (``ControlEnv``) with its fixed initial states.

    Attributes:
        problem: the task file as a typed problem.
        steps: steps taken since the last ``reset``.
    """

    def __init__(self, suite: str, index: int, controller: str = CONTROLLER) -> None:
        wrapper = require_libero("libero.libero.envs.env_wrapper")
        self.problem: LiberoProblem = task_problem(suite, index)
        self._states = init_states(suite, index)
        self.env = wrapper.ControlEnv(
            bddl_file_name=str(task_file(suite, index)), controller=controller, **ENV_OPTIONS
        )
        self.controller = controller
        if controller == CONTROLLER:  # every reset rebuilds the arm's controller from this
            self.env.env.robots[0].controller_config.update(
                kp=JOINT_KP, output_max=JOINT_DELTA_LIMIT, output_min=-JOINT_DELTA_LIMIT
            )
        low, high = self.env.env.action_spec
        self.action_low, self.action_high = np.asarray(low), np.asarray(high)
        self.steps = 0

    def reset(self, init_state: int, seed: int = 0) -> dict[str, np.ndarray]:
        """Reset to fixed initial state ``init_state`` (LIBERO's protocol: ``reset()``, then
        ``set_init_state``); returns the observation.

        LIBERO's ``reset()`` places the fixtures (cabinets, racks, the microwave, stoves)
        anew from its placement samplers, which draw from NumPy's global generator, and
        writes them into the model; an initial state sets joint positions and velocities
        only, so it leaves them where the draw put them (millimetres to a centimetre apart).
        LIBERO's own ``seed()`` seeds that generator before every reset, with
        ``episode_seeds(seed, init_state)``: an episode's scene no longer depends on what
        ran before it in the process.

        Raises:
            UsageError: ``init_state`` outside ``0 .. INIT_STATES-1``.
        """
        if not 0 <= init_state < INIT_STATES:
            raise UsageError(f"initial state {init_state} is outside 0-{INIT_STATES - 1}")
        self.env.seed(episode_seeds(seed, init_state)[0])
        self.env.reset()
        for robot in self.env.env.robots:
            _reset_grippers(robot.gripper)
        self.steps = 0
        return dict(self.env.set_init_state(self._states[init_state]))

    def step(self, action: np.ndarray) -> dict[str, np.ndarray]:
        """One control step (20 Hz); returns the observation.

        Raises:
            ControllerError: an action of the wrong shape or not finite (never sent).
        """
        action = np.asarray(action, dtype=float)
        if action.shape != self.action_low.shape or not np.isfinite(action).all():
            raise ControllerError(
                f"LIBERO action must be {self.action_low.shape[0]} finite values, got {action!r}"
            )
        obs, _, _, _ = self.env.step(np.clip(action, self.action_low, self.action_high))
        self.steps += 1
        return dict(obs)

    def check_success(self) -> bool:
        """The env's own verdict: the conjunction of the task file's goal atoms."""
        return bool(self.env.check_success())

    @property
    def sim(self) -> Any:
        """robosuite's ``MjSim`` (raw MuJoCo: ``sim.model._model``, ``sim.data._data``)."""
        return self.env.sim

    def close(self) -> None:
        """Free the simulator."""
        self.env.close()
