"""Turn a Minari data set into a project data set for one skill (h5py and json only).

The Minari data set must have the project's state and action layout: Box spaces of shapes
``(10,)`` and ``(7,)``. Each step's success, from which the rewards and terminations are
rebuilt, comes from either

- ``rewards``: a step succeeds when its reward is positive, or
- ``predicate``: the skill's success predicate over the recorded state after the step
  and the world state under ``infos/world_states`` (needed then).

World states absent from the source are stored as NaN (unknown): such data trains a skill,
but a skill graph cannot read effects from it.

Everything is checked before anything is written, each error naming the file and the field
(with the episode and step for an array): ``metadata.json`` (a JSON object, Box spaces of
the right shapes, a non-negative integer ``osg_seed``), every array's shape, dtype and
finite values, every action within the domain's ``action_bounds``, and at least one
episode. A refused import leaves the ``out`` file as it was.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import h5py
import numpy as np

from osg_control.data.datasets import (
    UNKNOWN,
    Dataset,
    Episode,
    load_dataset,
    write_episodes,
)
from osg_control.data.minari_export import DATA_DIR, MAIN_FILE, METADATA_FILE, minari_root
from osg_control.data.validation import check_step_fields, check_within
from osg_control.domain.base import Domain
from osg_control.domain.spaces import ACTION_DIM, OBS_DIM
from osg_control.domain.spec import SkillSpec
from osg_control.environment.arm_env import success_holds
from osg_control.errors import DatasetError
from osg_control.json_files import JSONFormatError, load_json, parse_json

SUCCESS_SOURCES = ("rewards", "predicate")


def resolve(source: str | Path) -> Path:
    """The ``data/`` folder of a Minari data set given as a folder or as an id under
    ``minari_root()``."""
    for candidate in (Path(source), minari_root() / str(source)):
        for data_dir in (candidate, candidate / DATA_DIR):
            if (data_dir / METADATA_FILE).is_file():
                return data_dir
    raise DatasetError(
        f"no Minari data set at {source!r} (looked for {METADATA_FILE} in it, in its "
        f"{DATA_DIR}/ and under {minari_root()})"
    )


def _read_metadata(data_dir: Path) -> dict[str, Any]:
    """The data set's ``metadata.json`` as a dict.

    Raises:
        DatasetError: the file cannot be read or is not a JSON object; names it.
    """
    path = data_dir / METADATA_FILE
    try:
        metadata = load_json(path)
    except (OSError, JSONFormatError) as err:
        raise DatasetError(f"{path}: not a readable JSON file ({err})") from err
    if not isinstance(metadata, dict):
        raise DatasetError(f"{path}: must hold a JSON object, got {type(metadata).__name__}")
    return metadata


def _space_shape(metadata: dict[str, Any], key: str, path: Path) -> tuple[int, ...]:
    """The shape of the Box space ``metadata[key]`` (a JSON string, as Minari writes it)."""
    try:
        space = parse_json(metadata[key], constants=True)
        if not isinstance(space, dict):
            raise ValueError("not a JSON object")
        kind, shape = space.get("type"), space.get("shape")
    except (KeyError, TypeError, ValueError) as err:
        raise DatasetError(f"{path}: field {key!r} is no readable space ({err})") from err
    if kind != "Box":
        raise DatasetError(f"{path}: field {key!r} is a {kind} space, expected a Box")
    if not isinstance(shape, list) or not all(type(n) is int for n in shape):
        raise DatasetError(f"{path}: field {key!r} has shape {shape!r}, expected a list of ints")
    return tuple(shape)


def _seed(metadata: dict[str, Any], path: Path) -> int:
    """The recorded ``osg_seed`` (0 when the data set has none)."""
    seed = metadata.get("osg_seed", 0)
    if type(seed) is not int or seed < 0:
        raise DatasetError(f"{path}: field 'osg_seed' must be a non-negative integer, got {seed!r}")
    return seed


def _check_recorded_skill(metadata: dict[str, Any], skill: SkillSpec, path: Path) -> None:
    """Refuse importing as ``skill`` a data set this package exported for another skill
    (its ``osg_skill`` metadata): the episodes were recorded for that skill's start and goal.

    Raises:
        DatasetError: naming both skills, or an unreadable ``osg_skill``.
    """
    if "osg_skill" not in metadata:
        return
    try:
        recorded = parse_json(metadata["osg_skill"])
        name = recorded["name"] if isinstance(recorded, dict) else None
    except (TypeError, KeyError, JSONFormatError) as err:
        raise DatasetError(f"{path}: field 'osg_skill' is no skill spec ({err})") from err
    if name != skill.name:
        raise DatasetError(
            f"{path}: the data set was recorded for skill {name!r} (osg_skill), but it is "
            f"imported as skill {skill.name!r}"
        )


def check_layout(metadata: dict[str, Any], skill: SkillSpec, path: Path) -> None:
    """Raise ``DatasetError`` naming both shapes if the spaces are not the skill's
    (``path``: the metadata file)."""
    for key, wanted in (("observation_space", (OBS_DIM,)), ("action_space", (ACTION_DIM,))):
        shape = _space_shape(metadata, key, path)
        if shape != wanted:
            raise DatasetError(
                f"{path}: {key} has shape {shape}, but skill {skill.name} needs {wanted}"
            )


def _successes(
    domain: Domain,
    skill: SkillSpec,
    next_obs: np.ndarray,
    rewards: np.ndarray,
    worlds: np.ndarray,
    how: str,
) -> np.ndarray:
    if how == "rewards":
        return rewards > 0
    end = domain.nodes[skill.end]
    return np.array(
        [
            success_holds(skill, end, obs[:3], float(obs[7]), domain.facts_of(world))
            for obs, world in zip(next_obs, worlds, strict=True)
        ],
        dtype=bool,
    )


SOURCE_FIELDS: dict[str, tuple[tuple[int, ...], Any]] = {
    "actions": ((ACTION_DIM,), np.float32),
    "rewards": ((), np.float32),
    "truncations": ((), np.bool_),
}
"""The per-step arrays read from a Minari episode (shape after the step axis, dtype kind)."""


def check_actions(actions: np.ndarray, bounds: tuple[float, ...], where: str) -> None:
    """Refuse an action outside the domain's per-step bounds (the env would never apply it).

    Raises:
        DatasetError: naming ``where``, the step, the component and the bound.
    """
    limit = np.asarray(bounds, dtype=np.float32)
    values = actions.astype(np.float32)
    check_within(values, -limit, limit, where, "actions", "the domain's action bounds")


def _episode(domain: Domain, group: h5py.Group, skill: SkillSpec, how: str, where: str) -> Episode:
    """One Minari episode group as an ``Episode``, every array checked first.

    Raises:
        DatasetError: naming ``where`` (file and episode), the field and the step: a wrong
            shape or dtype, a non-finite value, or an action outside the domain's bounds.
    """
    world_dim = len(domain.world_fields)
    source = {key: np.asarray(group[key][()]) for key in SOURCE_FIELDS}
    steps = check_step_fields(where, source, SOURCE_FIELDS)
    if steps == 0:
        raise DatasetError(f"{where}: the episode has no steps")
    observations = np.asarray(group["observations"][()])
    check_step_fields(
        where, {"observations": observations}, {"observations": ((OBS_DIM,), np.float32)}
    )
    if len(observations) != steps + 1:
        raise DatasetError(
            f"{where}: field 'observations' has {len(observations)} rows for {steps} steps; "
            f"expected {steps + 1} (the T states and the last next state)"
        )
    actions = source["actions"]
    check_actions(actions, domain.action_bounds, where)
    infos = group.get("infos")
    if infos is not None and "world_states" in infos:
        worlds = np.asarray(infos["world_states"][()])
        spec = {"infos/world_states": ((world_dim,), np.float32)}
        if check_step_fields(where, {"infos/world_states": worlds}, spec) != steps:
            raise DatasetError(
                f"{where}: field 'infos/world_states' has {len(worlds)} rows for {steps} steps "
                f"(domain {domain.name!r})"
            )
    elif how == "predicate":
        raise DatasetError(f"{where}: no infos/world_states, so --success predicate cannot run")
    else:
        worlds = np.full((steps, world_dim), np.nan)
    success = _successes(domain, skill, observations[1:], source["rewards"], worlds, how)
    return Episode(
        observations=observations[:-1].astype(np.float32),
        next_observations=observations[1:].astype(np.float32),
        actions=actions.astype(np.float32),
        rewards=success.astype(np.float32),
        terminations=success,
        truncations=source["truncations"].astype(bool),
        world_states=worlds.astype(np.float32),
    )


def import_minari(
    domain: Domain,
    source: str | Path,
    skill: str | SkillSpec,
    out: str | Path,
    success: str = "rewards",
) -> Dataset:
    """Convert a Minari data set (folder or id) into the project data set file ``out``.

    Raises:
        DatasetError: no data set there, spaces or arrays not the skill's layout (both
            shapes named), an unknown ``success`` source, or no world states for
            ``success="predicate"``.
    """
    if success not in SUCCESS_SOURCES:
        raise DatasetError(f"unknown success source {success!r}; known: rewards, predicate")
    skill = domain.skill(skill) if isinstance(skill, str) else skill
    data_dir = resolve(source)
    metadata = _read_metadata(data_dir)
    check_layout(metadata, skill, data_dir / METADATA_FILE)
    _check_recorded_skill(metadata, skill, data_dir / METADATA_FILE)
    seed = _seed(metadata, data_dir / METADATA_FILE)
    main = data_dir / MAIN_FILE
    try:
        with h5py.File(main, "r") as f:
            names = sorted(f, key=lambda name: int(name.rsplit("_", 1)[1]))
            episodes = [_episode(domain, f[n], skill, success, f"{main}:{n}") for n in names]
    except (OSError, KeyError, ValueError, IndexError, TypeError) as err:
        raise DatasetError(f"{main}: not a readable Minari HDF5 file ({err})") from err
    if not episodes:
        raise DatasetError(f"{main}: holds no episodes; nothing to import")
    collector = f"imported from Minari data set {metadata.get('dataset_id', source)}"
    return write_import(domain, skill, episodes, out, seed, collector, success)


def write_import(
    domain: Domain,
    skill: SkillSpec,
    episodes: list[Episode],
    out: str | Path,
    seed: int,
    collector: str,
    success: str,
) -> Dataset:
    """Write imported ``episodes`` as ``skill``'s data set file ``out`` (validated by
    ``write_episodes``; world states all NaN are declared unknown) and load it back."""
    attrs = {
        "domain": domain.name,
        "world_fields": ",".join(domain.world_fields),
        "skill": skill.to_json(),
        "seed": seed,
        "collector": collector,
        "success_from": success,
    }
    if any(np.isnan(e.world_states).all() for e in episodes):
        attrs["world_states"] = UNKNOWN
    write_episodes(Path(out), episodes, attrs)
    return load_dataset(out)
