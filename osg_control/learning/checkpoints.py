"""Skill checkpoints: actor weights as safetensors plus a JSON sidecar. Never pickle.

A skill ``NAME`` in a directory is two files:

``NAME.safetensors``
    The actor: ``layers.{i}.weight`` (in, out) and ``layers.{i}.bias`` (out,) float32, applied
    as ``x @ weight + bias`` with ReLU between layers and tanh after the last.
``NAME.json``
    Everything else: ``obs_dim``, ``action_dim``, ``hidden_sizes``, ``obs_mean`` and ``obs_std``
    (the actor sees ``normalise_observations(obs, obs_mean, obs_std)``), ``action_scale``
    (a physical action is the tanh output times this), ``skill_spec`` (``SkillSpec.to_json``
    as an object),
    ``train_config``, ``steps``, ``seed``, ``dataset_sha256``, ``weights_sha256`` (of the
    safetensors file, to detect corruption), ``package_version`` and ``format_version``.

Both files are written atomically (temp file + ``os.replace``), weights first.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from safetensors import SafetensorError
from safetensors.numpy import load as load_safetensors
from safetensors.numpy import save as save_safetensors

from osg_control import __version__
from osg_control.domain.spaces import ACTION_DIM, OBS_DIM
from osg_control.domain.spec import SkillSpec, skill_from_json
from osg_control.errors import CheckpointError, SkillSpecError
from osg_control.io_safety import atomic_write
from osg_control.json_files import parse_json, read_json_object

FORMAT_VERSION = 2
"""2: the sidecar carries ``normalisation_sha256`` (version 1, without it, still loads)."""
READABLE_VERSIONS = (1, 2)
NORMALISATION_KEYS = ("obs_mean", "obs_std", "action_scale")
"""The sidecar's normalisation fields, covered by its ``normalisation_sha256``: the weights'
hash does not cover them, and an edited mean or scale loaded and silently ruined the
skill."""
OBS_CLIP = 10.0
"""Normalised observations are clipped to this many std: a state far outside a skill's data
(e.g. a gripper command never seen in it) stays a bounded input."""
WEIGHTS_SUFFIX = ".safetensors"
SIDECAR_SUFFIX = ".json"
_SIDECAR_KEYS = (
    "format_version",
    "obs_dim",
    "action_dim",
    "hidden_sizes",
    "obs_mean",
    "obs_std",
    "action_scale",
    "skill_spec",
    "train_config",
    "steps",
    "seed",
    "dataset_sha256",
    "weights_sha256",
    "package_version",
)

Layer = tuple[np.ndarray, np.ndarray]


@dataclass
class Checkpoint:
    """A trained skill: its actor and what is needed to run it.

    Attributes:
        skill: the skill's specification.
        layers: ``[(weight (in, out), bias (out,)), ...]`` float32, ReLU between, tanh last.
        obs_mean: (obs_dim,) observation mean.
        obs_std: (obs_dim,) observation std (eps included).
        action_scale: (action_dim,) physical action per unit of tanh output (m, rad, -).
        train_config: the TD3+BC hyper-parameters (``TD3BCConfig.to_json_dict``).
        steps: updates trained.
        seed: the run's seed (the skill's own is ``td3bc.skill_seed(seed, skill.name)``).
        dataset_sha256: SHA-256 of the data set file trained on.
        package_version: osg-control version that trained it.
    """

    skill: SkillSpec
    layers: list[Layer]
    obs_mean: np.ndarray
    obs_std: np.ndarray
    action_scale: np.ndarray
    train_config: dict[str, Any]
    steps: int
    seed: int
    dataset_sha256: str
    package_version: str = __version__

    @property
    def obs_dim(self) -> int:
        """Observation size the actor takes."""
        return int(self.layers[0][0].shape[0])

    @property
    def action_dim(self) -> int:
        """Action size the actor returns."""
        return int(self.layers[-1][0].shape[1])

    @property
    def hidden_sizes(self) -> list[int]:
        """Widths of the hidden layers."""
        return [int(weight.shape[1]) for weight, _ in self.layers[:-1]]


def checkpoint_paths(directory: str | Path, name: str) -> tuple[Path, Path]:
    """The weights and sidecar paths of skill ``name`` in ``directory`` (``~`` expanded)."""
    directory = Path(directory).expanduser()
    return directory / f"{name}{WEIGHTS_SUFFIX}", directory / f"{name}{SIDECAR_SUFFIX}"


def sha256_file(path: str | Path) -> str:
    """Hex SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def values_sha256(values: Any) -> str:
    """The sha256 of JSON values as canonical text (sorted keys): the checksum a sidecar
    stores over the fields its weights' hash does not cover."""
    return hashlib.sha256(json.dumps(values, sort_keys=True).encode()).hexdigest()


def check_values_sha256(path: Path, values: Any, stored: Any, what: str) -> None:
    """Refuse sidecar values whose checksum is not the one written with them.

    Raises:
        CheckpointError: naming the file and ``what``.
    """
    if stored != values_sha256(values):
        raise CheckpointError(
            f"{path}: {what} do not match the sidecar's normalisation_sha256 (edited or "
            "corrupt); retrain or restore the checkpoint"
        )


def check_finite(path: Path, tensors: dict[str, np.ndarray]) -> None:
    """Refuse weights with a NaN or infinity.

    Raises:
        CheckpointError: naming the file and the first non-finite tensor.
    """
    for key, value in tensors.items():
        if not np.all(np.isfinite(value)):
            bad = int(np.size(value) - np.count_nonzero(np.isfinite(value)))
            raise CheckpointError(f"{path}: tensor {key!r} has {bad} non-finite value(s)")


def save_checkpoint(directory: str | Path, checkpoint: Checkpoint) -> tuple[Path, Path]:
    """Write ``<skill>.safetensors`` and ``<skill>.json`` into ``directory``, atomically.

    Args:
        directory: created if missing.
        checkpoint: what to write.

    Returns:
        The weights and sidecar paths.
    """
    weights_path, sidecar_path = checkpoint_paths(directory, checkpoint.skill.name)
    tensors: dict[str, np.ndarray] = {}
    for i, (weight, bias) in enumerate(checkpoint.layers):
        tensors[f"layers.{i}.weight"] = np.ascontiguousarray(weight, dtype=np.float32)
        tensors[f"layers.{i}.bias"] = np.ascontiguousarray(bias, dtype=np.float32)
    check_finite(weights_path, tensors)
    weights = save_safetensors(tensors, metadata={"skill": checkpoint.skill.name})
    sidecar = {
        "format_version": FORMAT_VERSION,
        "obs_dim": checkpoint.obs_dim,
        "action_dim": checkpoint.action_dim,
        "hidden_sizes": checkpoint.hidden_sizes,
        "obs_mean": checkpoint.obs_mean.tolist(),
        "obs_std": checkpoint.obs_std.tolist(),
        "action_scale": checkpoint.action_scale.tolist(),
        "skill_spec": json.loads(checkpoint.skill.to_json()),
        "train_config": checkpoint.train_config,
        "steps": checkpoint.steps,
        "seed": checkpoint.seed,
        "dataset_sha256": checkpoint.dataset_sha256,
        "weights_sha256": hashlib.sha256(weights).hexdigest(),
        "package_version": checkpoint.package_version,
    }
    sidecar["normalisation_sha256"] = values_sha256({k: sidecar[k] for k in NORMALISATION_KEYS})
    atomic_write(weights_path, lambda tmp: tmp.write_bytes(weights))
    sidecar_text = json.dumps(sidecar, indent=2) + "\n"
    atomic_write(sidecar_path, lambda tmp: tmp.write_text(sidecar_text))
    return weights_path, sidecar_path


_SIDECAR_TYPES: dict[str, type | tuple[type, ...]] = {
    "obs_dim": int,
    "action_dim": int,
    "hidden_sizes": list,
    "skill_spec": dict,
    "train_config": dict,
    "steps": int,
    "seed": int,
    "weights_sha256": str,
    "dataset_sha256": str,
    "package_version": str,
    "obs_mean": list,
    "obs_std": list,
    "action_scale": list,
}
"""The JSON type of each structural sidecar field (checked before use)."""


def _read_sidecar(path: Path, name: str) -> dict[str, Any]:
    sidecar = read_json_object(path, "checkpoint sidecar", CheckpointError)
    missing = [key for key in _SIDECAR_KEYS if key not in sidecar]
    if missing:
        raise CheckpointError(f"{path}: checkpoint sidecar lacks {', '.join(missing)}")
    if sidecar["format_version"] not in READABLE_VERSIONS:
        raise CheckpointError(
            f"{path}: checkpoint format {sidecar['format_version']}, this version reads "
            f"{', '.join(map(str, READABLE_VERSIONS))}"
        )
    if sidecar["format_version"] >= 2:
        if "normalisation_sha256" not in sidecar:
            raise CheckpointError(f"{path}: checkpoint sidecar lacks normalisation_sha256")
        check_values_sha256(
            path,
            {k: sidecar[k] for k in NORMALISATION_KEYS},
            sidecar["normalisation_sha256"],
            ", ".join(NORMALISATION_KEYS),
        )
    for key, kind in _SIDECAR_TYPES.items():
        value = sidecar[key]
        if not isinstance(value, kind) or isinstance(value, bool):
            raise CheckpointError(f"{path}: sidecar field {key!r} has the wrong type: {value!r}")
    sizes = sidecar["hidden_sizes"]
    if not all(isinstance(n, int) and not isinstance(n, bool) and n > 0 for n in sizes):
        raise CheckpointError(f"{path}: hidden_sizes must be positive integers, got {sizes}")
    spec = sidecar["skill_spec"]
    recorded = spec.get("name") if isinstance(spec, dict) else None
    if recorded != name:
        raise CheckpointError(
            f"{path}: checkpoint is for skill {recorded!r}, but skill {name!r} was requested"
        )
    return sidecar


def _weights_skill(data: bytes) -> str | None:
    """The skill a safetensors file was saved for (its ``skill`` metadata), if recorded."""
    size = int.from_bytes(data[:8], "little")
    header = parse_json(data[8 : 8 + size])  # valid: the file has loaded
    metadata = header.get("__metadata__") or {}
    return metadata.get("skill")


def _read_layers(path: Path, name: str, sidecar: dict[str, Any]) -> list[Layer]:
    if not path.is_file():
        raise CheckpointError(f"{path}: checkpoint weights not found")
    data = path.read_bytes()
    if hashlib.sha256(data).hexdigest() != sidecar["weights_sha256"]:
        raise CheckpointError(
            f"{path}: weights do not match the sidecar's weights_sha256 (corrupt or replaced)"
        )
    try:
        tensors = load_safetensors(data)
    except SafetensorError as err:
        raise CheckpointError(f"{path}: corrupt safetensors file ({err})") from err
    weights_skill = _weights_skill(data)
    if weights_skill != name:
        raise CheckpointError(
            f"{path}: the weights were saved for skill {weights_skill!r} (safetensors "
            f"metadata), but skill {name!r} was requested"
        )
    check_finite(path, tensors)
    sizes = [sidecar["obs_dim"], *sidecar["hidden_sizes"], sidecar["action_dim"]]
    layers = []
    for i, (fan_in, fan_out) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
        weight = tensors.get(f"layers.{i}.weight")
        bias = tensors.get(f"layers.{i}.bias")
        if weight is None or bias is None:
            raise CheckpointError(f"{path}: missing tensors of layer {i}")
        if weight.shape != (fan_in, fan_out) or bias.shape != (fan_out,):
            raise CheckpointError(
                f"{path}: layer {i} has weight {weight.shape} and bias {bias.shape}, the "
                f"sidecar implies {(fan_in, fan_out)} and {(fan_out,)}"
            )
        layers.append((weight.astype(np.float32), bias.astype(np.float32)))
    if len(tensors) != 2 * len(layers):
        raise CheckpointError(f"{path}: {len(tensors)} tensors, expected {2 * len(layers)}")
    return layers


def _vector(
    path: Path, sidecar: dict[str, Any], key: str, size: int, positive: bool = False
) -> np.ndarray:
    try:
        value = np.asarray(sidecar[key], dtype=np.float32)
    except (TypeError, ValueError) as err:
        raise CheckpointError(f"{path}: {key} must be {size} numbers ({err})") from err
    valid = np.isfinite(value) & (value > 0) if positive else np.isfinite(value)
    if value.shape != (size,) or not np.all(valid):
        kind = "positive" if positive else "finite"
        raise CheckpointError(f"{path}: {key} must be {size} {kind} numbers, got {sidecar[key]}")
    return value


def load_checkpoint(
    directory: str | Path, name: str, obs_dim: int = OBS_DIM, action_dim: int = ACTION_DIM
) -> Checkpoint:
    """Read and validate skill ``name``'s checkpoint from ``directory``.

    Args:
        directory: where ``<name>.safetensors`` and ``<name>.json`` are.
        name: the skill.
        obs_dim: observation size the caller will feed.
        action_dim: action size the caller expects back.

    Returns:
        The checkpoint.

    Raises:
        CheckpointError: naming the file, if a file is missing or corrupt, the sidecar or
            the weights are for another skill (both names given), or its dimensions differ
            from ``(obs_dim, action_dim)`` (both shapes given).
    """
    weights_path, sidecar_path = checkpoint_paths(directory, name)
    sidecar = _read_sidecar(sidecar_path, name)
    shape = (sidecar["obs_dim"], sidecar["action_dim"])
    if shape != (obs_dim, action_dim):
        raise CheckpointError(
            f"{sidecar_path}: checkpoint (obs_dim, action_dim) = {shape}, expected "
            f"{(obs_dim, action_dim)}"
        )
    layers = _read_layers(weights_path, name, sidecar)
    try:
        skill = skill_from_json(sidecar["skill_spec"])
    except SkillSpecError as err:
        raise CheckpointError(f"{sidecar_path}: invalid skill_spec ({err})") from err
    return Checkpoint(
        skill=skill,
        layers=layers,
        obs_mean=_vector(sidecar_path, sidecar, "obs_mean", obs_dim),
        obs_std=_vector(sidecar_path, sidecar, "obs_std", obs_dim, positive=True),
        action_scale=_vector(sidecar_path, sidecar, "action_scale", action_dim, positive=True),
        train_config=dict(sidecar["train_config"]),
        steps=int(sidecar["steps"]),
        seed=int(sidecar["seed"]),
        dataset_sha256=str(sidecar["dataset_sha256"]),
        package_version=str(sidecar["package_version"]),
    )


def require_skills(directory: str | Path, names: Sequence[str]) -> None:
    """Check that ``directory`` holds both checkpoint files of every skill in ``names``.

    Raises:
        CheckpointError: the folder is missing, or lacks skills (naming the folder and
            every missing skill).
    """
    directory = Path(directory).expanduser()
    if not directory.is_dir():
        raise CheckpointError(f"{directory}: checkpoint directory not found")
    missing = [
        name for name in names if not all(p.is_file() for p in checkpoint_paths(directory, name))
    ]
    if missing:
        raise CheckpointError(
            f"{directory}: no checkpoint of skill(s) {', '.join(missing)} (each needs "
            f"NAME{WEIGHTS_SUFFIX} and NAME{SIDECAR_SUFFIX}); train them with `osg train`"
        )


ACTION_SCALE_RTOL = 1e-4
"""How far a checkpoint's ``action_scale`` may be from its domain's action bounds (relative):
float32 rounding, nothing more."""


def check_action_scale(path: Path, action_scale: np.ndarray, bounds: Sequence[float]) -> None:
    """Check that a checkpoint's ``action_scale`` is its domain's ``action_bounds``.

    Raises:
        CheckpointError: naming the sidecar ``path``, both vectors given.
    """
    expected = np.asarray(bounds, dtype=float)
    scale = np.asarray(action_scale, dtype=float)
    if scale.shape != expected.shape or not np.allclose(
        scale, expected, rtol=ACTION_SCALE_RTOL, atol=0.0
    ):
        raise CheckpointError(
            f"{path}: action_scale {scale.round(6).tolist()} is not the domain's action "
            f"bounds {expected.round(6).tolist()} (trained for another domain, or edited)"
        )


def normalise_observations(
    observations: np.ndarray, mean: np.ndarray, std: np.ndarray
) -> np.ndarray:
    """The actor's and critics' input: ``(obs - mean) / std`` clipped to ``±OBS_CLIP``."""
    return np.clip((observations - mean) / std, -OBS_CLIP, OBS_CLIP)
