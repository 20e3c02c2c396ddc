"""Read and check a Minari data set in the D4RL kitchen layout (h5py and json only).

The layout, as Minari ships ``D4RL/kitchen/complete-v2``, ``mixed-v2`` and ``partial-v2``
(recorded by replaying the D4RL teleoperation logs in ``FrankaKitchen-v1`` with
``remove_task_when_completed=False``; Farama's minari-dataset-generation-scripts)::

    data/metadata.json    observation_space: a Dict space with ``observation`` (Box (59,)),
                          ``achieved_goal`` and ``desired_goal``; action_space: Box (9,)
    data/main_data.hdf5   episode_<N>/
        observations/observation            (T+1, 59) the env's observation array
        observations/achieved_goal/<task>   (T+1, d)  the task's object qpos
        observations/desired_goal/<task>    (T+1, d)  its goal
        actions (T, 9) joint-velocity actions in [-1, 1]; rewards, terminations,
        truncations (T,); infos/ optional (the shipped files hold only ``infos/ctrl``)

Completion steps come from ``infos/step_task_completions/<task>`` ((T,) bool, True at the
step a task completed: what a Minari step callback recording the env's
``step_task_completions`` would store) when an episode has it, else by the library's rule:
the first step after which ``norm(achieved - desired) < BONUS_THRESH``, on the file's goals
for the tasks it lists and, for the library's other tasks (the shipped files list only their
four goal tasks, while the human did others too), on the observed object qpos against
``OBS_ELEMENT_GOALS``. A task whose rule holds at the first observation is done at the
start, not completed.
Everything is checked on reading; errors name the file, the episode, the field and the step.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from osg_control.data.minari_export import MAIN_FILE, METADATA_FILE
from osg_control.data.minari_import import _read_metadata, _space_shape, resolve
from osg_control.data.validation import check_step_fields
from osg_control.errors import DatasetError
from osg_control.franka.perception import OBJECT_QPOS
from osg_control.json_files import parse_json

OBSERVATION = "observations/observation"
FLAGS = "infos/step_task_completions"
STEP_FIELDS: dict[str, tuple[tuple[int, ...], Any]] = {
    "actions": ((9,), np.float32),
    "rewards": ((), np.float32),
    "terminations": ((), np.bool_),
    "truncations": ((), np.bool_),
}
"""The per-step (T) arrays of an episode: shape after the step axis, dtype kind."""
FIRST_OBJECT = 9
"""The env's qpos index of the observation's first object qpos (``OBJECT_QPOS``)."""


@dataclass
class KitchenEpisode:
    """One checked source episode: T+1 observation rows, T actions, goals per task."""

    name: str
    observations: np.ndarray
    actions: np.ndarray
    achieved: dict[str, np.ndarray]
    desired: dict[str, np.ndarray]
    flags: dict[str, np.ndarray] | None

    def __len__(self) -> int:
        return len(self.actions)


def _observation_space(metadata: dict[str, Any]) -> dict[str, Any] | None:
    """The serialised observation space's subspaces if it is a Dict space, else None."""
    try:
        space = parse_json(metadata["observation_space"], constants=True)
    except (KeyError, TypeError, ValueError):
        return None
    if not isinstance(space, dict) or space.get("type") != "Dict":
        return None
    subspaces = space.get("subspaces")
    return subspaces if isinstance(subspaces, dict) else None


def is_d4rl_layout(source: str | Path) -> bool:
    """Whether a Minari data set (folder or id) has the D4RL kitchen layout: a Dict
    observation space with ``observation`` and ``achieved_goal`` (used to pick the importer).

    Raises:
        DatasetError: no Minari data set there, or an unreadable ``metadata.json``.
    """
    subspaces = _observation_space(_read_metadata(resolve(source)))
    return subspaces is not None and {"observation", "achieved_goal"} <= set(subspaces)


def check_spaces(metadata: dict[str, Any], path: Path) -> None:
    """Refuse spaces other than the layout's: ``observation`` Box (59,), ``achieved_goal``
    and ``desired_goal`` Dicts, actions Box (9,) (``path``: the metadata file, named)."""
    subspaces = _observation_space(metadata)
    if subspaces is None:
        raise DatasetError(f"{path}: field 'observation_space' is not a Dict space")
    for key in ("achieved_goal", "desired_goal"):
        if not isinstance(subspaces.get(key), dict) or subspaces[key].get("type") != "Dict":
            raise DatasetError(f"{path}: field 'observation_space' has no Dict {key!r}")
    key = "observation_space.observation"
    shape = _space_shape({key: json.dumps(subspaces.get("observation"))}, key, path)
    if shape != (59,):
        raise DatasetError(f"{path}: field {key!r} has shape {shape}, expected (59,)")
    actions = _space_shape(metadata, "action_space", path)
    if actions != (9,):
        raise DatasetError(f"{path}: field 'action_space' has shape {actions}, expected (9,)")


def _array(group: h5py.Group, key: str, where: str) -> np.ndarray:
    """The data set ``key`` of ``group`` as an array; a missing one is a ``DatasetError``."""
    item = group.get(key)
    if not isinstance(item, h5py.Dataset):
        raise DatasetError(f"{where}: missing field {key!r}")
    return np.asarray(item[()])


def _per_task(group: h5py.Group, key: str, where: str) -> dict[str, np.ndarray]:
    """The per-task arrays under the group ``key`` (e.g. ``observations/achieved_goal``)."""
    sub = group.get(key)
    if not isinstance(sub, h5py.Group):
        raise DatasetError(f"{where}: missing field {key!r} (a group of per-task arrays)")
    arrays = {}
    for task, item in sub.items():
        if not isinstance(item, h5py.Dataset):
            raise DatasetError(f"{where}: field '{key}/{task}' is not an array")
        arrays[task] = np.asarray(item[()])
    return arrays


def _check_rows(
    where: str, arrays: dict[str, np.ndarray], dims: dict[str, tuple[int, ...]], kind: Any
) -> int:
    """``check_step_fields`` for arrays of one length, each of its own row shape."""
    return check_step_fields(where, arrays, {k: (dims[k], kind) for k in arrays})


def _check_goals(
    where: str, achieved: dict[str, np.ndarray], desired: dict[str, np.ndarray]
) -> None:
    """Both goal groups name the same tasks, each (T+1, d) with the library's d for its
    tasks (others: achieved and desired alike)."""
    from gymnasium_robotics.envs.franka_kitchen.kitchen_env import OBS_ELEMENT_GOALS

    if not achieved:
        raise DatasetError(f"{where}: field 'observations/achieved_goal' names no task")
    for have, lack in (("achieved_goal", "desired_goal"), ("desired_goal", "achieved_goal")):
        first, second = (achieved, desired) if have == "achieved_goal" else (desired, achieved)
        odd = sorted(set(first) - set(second))
        if odd:
            raise DatasetError(
                f"{where}: missing field 'observations/{lack}/{odd[0]}' ({have} has it)"
            )
    for task, values in achieved.items():
        known = OBS_ELEMENT_GOALS.get(task)
        width = len(known) if known is not None else values.shape[-1] if values.ndim else 0
        for group, array in (("achieved_goal", values), ("desired_goal", desired[task])):
            if array.ndim != 2 or array.shape[1] != width:
                raise DatasetError(
                    f"{where}: field 'observations/{group}/{task}' has shape {array.shape}, "
                    f"expected (T+1, {width})"
                )


def read_episode(group: h5py.Group, where: str) -> KitchenEpisode:
    """One episode group, every field checked (shape, dtype, finite, actions in [-1, 1]).

    Raises:
        DatasetError: naming ``where`` (file and episode), the field and the step.
    """
    steps_arrays = {key: _array(group, key, where) for key in STEP_FIELDS}
    steps = check_step_fields(where, steps_arrays, STEP_FIELDS)
    if steps == 0:
        raise DatasetError(f"{where}: the episode has no steps")
    observations = _array(group, OBSERVATION, where)
    achieved = _per_task(group, "observations/achieved_goal", where)
    desired = _per_task(group, "observations/desired_goal", where)
    _check_goals(where, achieved, desired)
    rows = {
        OBSERVATION: observations,
        **{f"observations/achieved_goal/{t}": a for t, a in achieved.items()},
        **{f"observations/desired_goal/{t}": d for t, d in desired.items()},
    }
    dims = {key: tuple(array.shape[1:]) for key, array in rows.items()}
    dims[OBSERVATION] = (59,)
    if _check_rows(where, rows, dims, np.float32) != steps + 1:
        raise DatasetError(
            f"{where}: field {OBSERVATION!r} has {len(observations)} rows for {steps} steps; "
            f"expected {steps + 1} (the T states and the last next state)"
        )
    actions = steps_arrays["actions"]
    outside = np.argwhere(np.abs(actions) > 1.0)
    if len(outside):
        step, component = (int(i) for i in outside[0])
        raise DatasetError(
            f"{where}: field 'actions' at step {step}, component {component}: "
            f"{float(actions[step, component])!r} is outside the env's action space [-1, 1]"
        )
    flags = None
    if FLAGS in group:
        flags = _per_task(group, FLAGS, where)
        _check_rows(
            where,
            {f"{FLAGS}/{t}": f for t, f in flags.items()},
            {f"{FLAGS}/{t}": () for t in flags},
            np.bool_,
        )
        for task, values in flags.items():
            if len(values) != steps:
                raise DatasetError(
                    f"{where}: field '{FLAGS}/{task}' has {len(values)} steps, others {steps}"
                )
    return KitchenEpisode(
        where, observations.astype(float), actions.astype(float), achieved, desired, flags
    )


def read_source(source: str | Path) -> tuple[Path, dict[str, Any], list[KitchenEpisode]]:
    """The data folder, metadata and every checked episode (in index order) of a D4RL
    kitchen-layout Minari data set (folder or id under the Minari root).

    Raises:
        DatasetError: no data set there, spaces not the layout's, an unreadable HDF5 file,
            a bad field (named with its episode and step), or no episodes.
    """
    data_dir = resolve(source)
    metadata = _read_metadata(data_dir)
    check_spaces(metadata, data_dir / METADATA_FILE)
    main = data_dir / MAIN_FILE
    try:
        with h5py.File(main, "r") as f:
            names = sorted(f, key=lambda name: int(name.rsplit("_", 1)[1]))
            episodes = [read_episode(f[n], f"{main}:{n}") for n in names]
    except (OSError, KeyError, ValueError, IndexError, TypeError) as err:
        raise DatasetError(f"{main}: not a readable Minari HDF5 file ({err})") from err
    if not episodes:
        raise DatasetError(f"{main}: holds no episodes; nothing to import")
    return data_dir, metadata, episodes


def _goal_rows(episode: KitchenEpisode) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per task the (T+1, d) values and goals the rule compares: ``achieved_goal`` against
    ``desired_goal`` for the tasks the file lists; for the library's other tasks (the
    shipped files list only their four goal tasks) the observed object qpos against the
    library's goal."""
    from gymnasium_robotics.envs.franka_kitchen.kitchen_env import (
        OBS_ELEMENT_GOALS,
        OBS_ELEMENT_INDICES,
    )

    rows = {task: (a, episode.desired[task]) for task, a in episode.achieved.items()}
    objects = episode.observations[:, OBJECT_QPOS]
    for task, goal in OBS_ELEMENT_GOALS.items():
        if task not in rows:
            rows[task] = (objects[:, np.asarray(OBS_ELEMENT_INDICES[task]) - FIRST_OBJECT], goal)
    return rows


def completions(episode: KitchenEpisode) -> tuple[list[tuple[int, str]], list[str]]:
    """The (step, task) completions of an episode, in step order, and the tasks already done
    at its first observation (never completed by it), by the module docstring's rule."""
    if episode.flags is not None:
        events = [(int(np.flatnonzero(f)[0]), task) for task, f in episode.flags.items() if f.any()]
        return sorted(events), []
    from gymnasium_robotics.envs.franka_kitchen.kitchen_env import BONUS_THRESH

    events, at_start = [], []
    for task, (values, goals) in _goal_rows(episode).items():
        done = np.linalg.norm(values - goals, axis=1) < BONUS_THRESH
        if done[0]:
            at_start.append(task)
        elif done.any():
            events.append((int(np.flatnonzero(done)[0]) - 1, task))
    return sorted(events), sorted(at_start)
