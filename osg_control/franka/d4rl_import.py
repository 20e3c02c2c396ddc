"""Import the D4RL kitchen human data (Minari layout) as franka-kitchen skill data sets.

``import_d4rl(domain, source, out)`` reads a Minari data set in the D4RL kitchen layout
(``franka.d4rl_source``, every field checked before anything is written), converts each
episode into this domain's 10-D state and 7-D action, cuts it at its task completions and
writes ``out/<skill>.h5`` for each skill that got an episode. A refused import leaves
``out`` as it was: all files are written into a staging folder first, then renamed in.

Conversion of an episode (step t goes from observation row t to row t+1 with action t):

- State: the ``env`` perception's own readout (``FrankaSensors.env_readout`` of an adapter
  on a fresh FrankaKitchen-v1, its grasp memory reset per episode) of each recorded 59-D
  observation: TCP by forward kinematics of the observed arm joints, its quaternion,
  the gripper command (below), the finger servos' effort while a grasp is detected, the
  finger width. World states: the same readout's world vector after each step (observed
  object qpos, grasp by finger width).
- Action: ``[dx, dy, dz]`` the TCP's observed displacement over the step (state t+1 minus
  state t) and ``[da, db, dg]`` the world-frame rotation vector from its orientation at t
  to that at t+1, each part scaled as a whole into the domain's ``action_bounds`` (4 cm,
  0.2 rad) where larger, as the scripted data's actions are (``scale_into``). Gripper: the
  recorded finger command (mean of action components 7-8; + opens, - closes) beyond
  ``GRIP_DEADBAND`` sets the latched gripper command; the action's gripper component is
  that command (+-1) on the step it changes and 0 otherwise (the scripted data's way).

Segmentation: an episode's completions (``d4rl_source.completions``) in step order; the
steps after the previous completion (or from the start) up to and including the step at
which a task completes are one episode of the skill that completes it (of its
``SUBTASK_CHAINS`` skills the one adding its fact: ``pull-microwave``, ``push-kettle``...),
rewarded and terminated at that last step only. Completions of tasks without a skill here
are skipped (their segment dropped, counted); steps after the last completion are dropped.

Limits: the action is the motion the human's joint command achieved, not the command this
domain's IK needs for it (the adapter's servos cover 60-80 % of a command in one step), so
replayed actions move the TCP less than the human did. A segment holds all the human did
between two completions, labelled as the completing skill: the approach from wherever the
previous subtask ended (here the movement skills), and for a door its grasp; the release
after a door's completion opens the next segment. Success is the library's task
completion, not the skill's end-node predicate. Tested on synthetic files only.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections import Counter
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from osg_control.control.rotations import quat_to_matrix, rotation_error
from osg_control.data.datasets import Episode, dataset_bytes, write_episodes
from osg_control.data.validation import check_within
from osg_control.domain.base import Domain
from osg_control.domain.spec import SkillSpec
from osg_control.environment.actions import scale_into
from osg_control.environment.success import GRIPPER_CLOSED_CMD, GRIPPER_OPEN_CMD
from osg_control.errors import DatasetError, UsageError
from osg_control.franka.d4rl_source import KitchenEpisode, completions, read_source
from osg_control.franka.domain import SUBTASK_CHAINS, TASK_FACTS
from osg_control.franka.perception import FrankaSensors
from osg_control.io_safety import check_output_dir, output_errors

DOMAIN = "franka-kitchen"
GRIP_DEADBAND = 0.05
"""|recorded finger command| above which it sets the gripper: the D4RL finger actions are
servo-target offsets ((target - observed) / (2 dt) by Minari's generation script), so a
whole open or close is a fraction of 1, and a hand closed on a handle keeps a steady
negative command; below the deadband (observation noise, holding still) it holds."""


@dataclass
class D4RLImport:
    """What an import did: per skill its file, task, episodes and steps; what it skipped."""

    source: str
    out: str
    episodes: int = 0
    skills: dict[str, dict[str, Any]] = field(default_factory=dict)
    skipped_tasks: dict[str, int] = field(default_factory=dict)
    """Completions of tasks that no skill of this domain completes (their segments dropped)."""
    done_at_start: dict[str, int] = field(default_factory=dict)
    same_step: dict[str, int] = field(default_factory=dict)
    """Completions at the same step as an earlier one (an empty segment)."""
    dropped_steps: int = 0
    scaled_actions: int = 0
    """Steps whose TCP motion exceeded the action bounds and was scaled into them."""
    completions_from: dict[str, int] = field(default_factory=dict)
    """Episodes whose completions came from ``infos`` and from the goals."""

    def to_json(self) -> dict[str, Any]:
        """The summary as a JSON-ready dict."""
        return asdict(self)

    def lines(self) -> list[str]:
        """The summary for humans: a line per skill written, one for what was left out."""
        rows = [
            f"{row['path']}: skill {name} ({row['task']}), {row['episodes']} episodes, "
            f"{row['steps']} steps"
            for name, row in self.skills.items()
        ]
        rows.append(
            f"{self.episodes} source episodes; skipped completions "
            f"{self.skipped_tasks or 'none'}, {self.dropped_steps} steps outside a segment, "
            f"{self.scaled_actions} actions scaled into the bounds"
        )
        return rows


def completing_skill(domain: Domain, task: str) -> SkillSpec | None:
    """The domain's skill that completes ``task`` (adds its fact), None for other tasks."""
    for name in SUBTASK_CHAINS.get(task, ()):
        skill = domain.skill(name)
        if TASK_FACTS[task][0] in skill.add_effects:
            return skill
    return None


def gripper_commands(actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The action's gripper component per step (T,) and the latched command per observation
    row (T+1,), open at the start, from the recorded finger commands (module docstring)."""
    finger = actions[:, 7:9].mean(axis=1)
    command, latched, components = GRIPPER_OPEN_CMD, [GRIPPER_OPEN_CMD], np.zeros(len(actions))
    for t, value in enumerate(finger):
        wanted = GRIPPER_CLOSED_CMD if value < -GRIP_DEADBAND else command
        wanted = GRIPPER_OPEN_CMD if value > GRIP_DEADBAND else wanted
        if wanted != command:
            components[t] = command = wanted
        latched.append(command)
    return components, np.array(latched)


def tcp_actions(states: np.ndarray, bounds: np.ndarray) -> tuple[np.ndarray, int]:
    """The (T, 6) TCP displacement and rotation vector between consecutive states, each part
    scaled into ``bounds`` (7,); and how many steps needed scaling."""
    actions, scaled = np.zeros((len(states) - 1, 6)), 0
    for t in range(len(states) - 1):
        move = states[t + 1, :3] - states[t, :3]
        turn = rotation_error(quat_to_matrix(states[t, 3:7]), quat_to_matrix(states[t + 1, 3:7]))
        scaled += bool(np.any(np.abs(move) > bounds[0]) or np.any(np.abs(turn) > bounds[3]))
        actions[t, :3], actions[t, 3:] = scale_into(move, bounds[0]), scale_into(turn, bounds[3])
    return np.clip(actions, -bounds[:6], bounds[:6]), scaled


def convert(
    sensors: FrankaSensors, episode: KitchenEpisode, bounds: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """An episode's states (T+1, 10), world states (T+1, W), actions (T, 7) and the number of
    scaled steps, by the ``env`` perception's readout (module docstring)."""
    components, latched = gripper_commands(episode.actions)
    sensors.forget()
    states, worlds = [], []
    for row, command in zip(episode.observations, latched, strict=True):
        state, _joints, world = sensors.env_readout(row, float(command))
        states.append(state)
        worlds.append(world)
    states_array = np.array(states)
    moves, scaled = tcp_actions(states_array, bounds)
    return states_array, np.array(worlds), np.column_stack([moves, components]), scaled


def _episode(
    states: np.ndarray, worlds: np.ndarray, actions: np.ndarray, start: int, stop: int
) -> Episode:
    """Steps ``start``..``stop`` (inclusive) as an ``Episode`` that succeeds at ``stop``."""
    steps = stop + 1 - start
    success = np.zeros(steps, dtype=bool)
    success[-1] = True
    return Episode(
        observations=states[start : stop + 1].astype(np.float32),
        next_observations=states[start + 1 : stop + 2].astype(np.float32),
        actions=actions[start : stop + 1].astype(np.float32),
        rewards=success.astype(np.float32),
        terminations=success,
        truncations=np.zeros(steps, dtype=bool),
        world_states=worlds[start + 1 : stop + 2].astype(np.float32),
    )


def _write_all(out: Path, files: dict[str, tuple[list[Episode], dict[str, Any]]]) -> None:
    """Write every ``<skill>.h5`` into a staging folder in ``out``, then rename them in: a
    refused or failed write leaves ``out``'s files as they were."""
    with output_errors(out):
        staging = Path(tempfile.mkdtemp(prefix=".d4rl-import.", dir=out))
    try:
        for name, (episodes, attrs) in files.items():
            write_episodes(staging / f"{name}.h5", episodes, attrs)
        for name in files:
            with output_errors(out / f"{name}.h5"):
                os.replace(staging / f"{name}.h5", out / f"{name}.h5")
    finally:
        shutil.rmtree(staging, ignore_errors=True)


JOINT_SLACK = 0.05
"""How far [rad] an observed arm joint may lie past the env's limit: the env's own
observation noise (``robot_noise_ratio``) and its position servo's overshoot, with
margin. A value beyond (1e30 rad) is no pose the arm can take."""


def check_joint_limits(episode: KitchenEpisode, lower: np.ndarray, upper: np.ndarray) -> None:
    """Refuse an episode whose observed arm joints (the observation's first 7 values) lie
    past the arm's limits by more than ``JOINT_SLACK``.

    Raises:
        DatasetError: naming the episode, the step, the joint, its value and its range.
    """
    check_within(
        episode.observations[:, : len(lower)],
        lower - JOINT_SLACK,
        upper + JOINT_SLACK,
        episode.name,
        "observations/observation",
        "the arm's joint limits [rad] (no pose the arm can take)",
    )


def import_d4rl(domain: Domain, source: str | Path, out: str | Path) -> D4RLImport:
    """Convert a D4RL kitchen-layout Minari data set (folder or id) into one data set file
    per skill in the folder ``out``; returns the summary.

    Raises:
        UsageError: ``domain`` is not franka-kitchen.
        DatasetError: the source refused (named: file, episode, field, step), or no
            episode completes a task that a skill of the domain completes.
        OutputError: ``out`` cannot be written, or lies inside the installed package.
    """
    if domain.name != DOMAIN:
        raise UsageError(
            f"--domain {domain.name}: a D4RL kitchen-layout data set imports only into "
            f"--domain {DOMAIN} (its 59-D observation and 9-D joint actions are that env's)"
        )
    from osg_control.franka.envs import make_franka_env

    data_dir, metadata, source_episodes = read_source(source)
    summary = D4RLImport(str(source), str(out), episodes=len(source_episodes))
    bounds = np.asarray(domain.action_bounds, dtype=float)
    per_skill: dict[str, list[Episode]] = {}
    counts: dict[str, Counter[str]] = {k: Counter() for k in ("skip", "start", "same", "from")}
    adapter = make_franka_env()
    lower, upper = np.array(adapter.robot.arm.lower), np.array(adapter.robot.arm.upper)
    for episode in source_episodes:  # all checked before anything is converted or written
        check_joint_limits(episode, lower, upper)
    try:
        for episode in source_episodes:
            events, at_start = completions(episode)
            counts["start"].update(at_start)
            counts["from"]["infos" if episode.flags is not None else "goals"] += 1
            states, worlds, actions, scaled = convert(adapter.sensors, episode, bounds)
            summary.scaled_actions += scaled
            begin = 0
            for step, task in events:
                if step < begin:
                    counts["same"][task] += 1
                    continue
                skill = completing_skill(domain, task)
                if skill is None:
                    counts["skip"][task] += 1
                    summary.dropped_steps += step + 1 - begin
                else:
                    per_skill.setdefault(skill.name, []).append(
                        _episode(states, worlds, actions, begin, step)
                    )
                begin = step + 1
            summary.dropped_steps += len(episode) - begin
    finally:
        adapter.close()
    summary.skipped_tasks, summary.done_at_start = dict(counts["skip"]), dict(counts["start"])
    summary.same_step, summary.completions_from = dict(counts["same"]), dict(counts["from"])
    if not per_skill:
        raise DatasetError(
            f"{data_dir}: no episode completes a task that a skill of {DOMAIN} completes "
            f"(skipped: {summary.skipped_tasks or 'none'}); nothing to import"
        )
    size = sum(
        dataset_bytes(sum(map(len, e)), len(e), len(domain.world_fields))
        for e in per_skill.values()
    )
    target = check_output_dir(out, "data folder", size)
    dataset_id = metadata.get("dataset_id", str(source))
    files = {}
    for name, episodes in sorted(per_skill.items()):
        attrs = {
            "domain": domain.name,
            "world_fields": ",".join(domain.world_fields),
            "skill": domain.skill(name).to_json(),
            "seed": 0,
            "collector": f"imported from D4RL kitchen-layout Minari data set {dataset_id} "
            "(human teleoperation), segmented at task completions",
            "success_from": "task completion",
        }
        files[name] = (episodes, attrs)
        task = next(t for t in SUBTASK_CHAINS if name in SUBTASK_CHAINS[t])
        summary.skills[name] = {
            "path": str(target / f"{name}.h5"),
            "task": task,
            "episodes": len(episodes),
            "steps": sum(len(e) for e in episodes),
        }
    _write_all(target, files)
    return summary
