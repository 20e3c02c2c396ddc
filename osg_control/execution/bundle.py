"""The model bundle: a defaults folder's skills, classifier and the success rates measured
with them, with the perception, noise and filter the rates were measured at; the one
owner of the folder's ``manifest.json``: its keys, reading, checking and writing.

A bundle is a folder of the shipped defaults' layout (``skills/``, ``classifier/``,
``manifest.json``); ``ModelBundle`` is its manifest, typed. The manifest records
``success_rates`` (each skill's measured Table I rate at the deployment noise: the plan
costs ``round(-ln p * 1000)``, ``measured_graph``), ``perception``, ``noise``,
``filter_gain``, ``motion_model`` (the TCP filter's fit) and provenance (``command``,
``seed``, ``datasets_sha256``...). ``execution.defaults.load_defaults`` and ``osg plan``
read it through here. Reading needs no model (no torch).
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from osg_control.control.estimator import check_motion_model
from osg_control.domain.base import Domain
from osg_control.errors import CheckpointError, OSGError
from osg_control.io_safety import atomic_write
from osg_control.json_files import is_json_number, read_json_object
from osg_control.perception.spec import PerceptionSpec
from osg_control.planning.graph import SkillGraph, graph_from_specs

LOGGER = logging.getLogger(__name__)
DEPLOYMENT_NOISE = 0.02
"""The paper protocol's observation noise [m] whose Table I rates become the plan costs
(the paper's 2 cm)."""
SKILLS_DIR = "skills"
"""The bundle's skill checkpoint folder (one ``<skill>.safetensors`` + ``.json`` each)."""
CLASSIFIER_DIR = "classifier"
"""The bundle's state->skill classifier folder."""
MANIFEST = "manifest.json"
"""The bundle's manifest file."""
RATES_KEY = "success_rates"
"""The manifest's map of skill name -> measured success rate (the plan costs)."""
MOTION_KEY = "motion_model"
"""The manifest key of the TCP filter's motion model ``[k_now, k_prev]``."""
PERCEPTION_KEY = "perception"
NOISE_KEY = "noise"
FILTER_KEY = "filter_gain"
RATES_FROM_KEY = "success_rates_from"
_OWN_KEYS = (PERCEPTION_KEY, NOISE_KEY, FILTER_KEY, RATES_KEY, RATES_FROM_KEY, MOTION_KEY)
"""The manifest keys ``ModelBundle`` types; every other key is kept as ``provenance``."""


@dataclass(frozen=True)
class ModelBundle:
    """A defaults folder's models and what their success rates were measured under.

    Attributes:
        directory: the folder (``skills/``, ``classifier/``, ``manifest.json``).
        success_rates: skill name -> measured success rate (the plan costs,
            ``round(-ln p * 1000)``); empty before any were measured.
        perception: the perception the rates were measured under (None: not recorded,
            e.g. a manifest written before perceptions existed).
        noise: the paper protocol's TCP noise sigma [m] of the rates (None: not recorded).
        filter_gain: the TCP filter gain the policies ran with (None: raw observations).
        motion_model: the TCP filter's ``(k_now, k_prev)`` fitted on the data the
            skills were trained on (``pipeline.motion``; None: not fitted, the executor
            then uses ``control.estimator.MOTION_MODEL``).
        rates_from: how the rates were measured, in words (the manifest's
            ``success_rates_from``; by default ``describe_measurement()`` when there are
            rates).
        provenance: the manifest's other keys as read or to be written (domain, command,
            seed, scale, package version, git commit, data set hashes).
    """

    directory: Path
    success_rates: dict[str, float] = field(default_factory=dict)
    perception: PerceptionSpec | None = None
    noise: float | None = None
    filter_gain: float | None = None
    motion_model: tuple[float, float] | None = None
    rates_from: str | None = None
    provenance: dict[str, Any] = field(default_factory=dict)

    @property
    def policies_dir(self) -> Path:
        """The skill checkpoint folder (``execution.defaults.load_skill_policies``)."""
        return self.directory / SKILLS_DIR

    @property
    def classifier_dir(self) -> Path:
        """The classifier folder (``classifier.model.StateClassifier.load``)."""
        return self.directory / CLASSIFIER_DIR

    def graph(self, domain: Domain) -> SkillGraph:
        """The domain's skill graph with these success rates as costs (uniform for a
        skill without one)."""
        return graph_from_specs(domain, success_rates=self.success_rates)

    @property
    def manifest_path(self) -> Path:
        """``<directory>/manifest.json``."""
        return self.directory / MANIFEST

    def __post_init__(self) -> None:
        if self.success_rates and self.rates_from is None:
            object.__setattr__(self, "rates_from", self.describe_measurement())

    def describe_measurement(self) -> str:
        """How the success rates were measured, in words, from the perception, noise and
        filter gain (the default ``rates_from``)."""
        noise = "" if self.noise is None else f" at sigma = {self.noise:g} m"
        seen = "" if self.perception is None else f", perception {self.perception.name}"
        gain = (
            ", raw observations" if self.filter_gain is None
            else f", TCP filter gain {self.filter_gain:g}"
        )  # fmt: skip
        return f"Table I{noise}{seen}{gain}"

    def with_rates(
        self,
        rates: Mapping[str, float],
        noise: float,
        perception: PerceptionSpec | None = None,
        filter_gain: float | None = None,
    ) -> ModelBundle:
        """This bundle with ``rates`` measured at the paper protocol's TCP noise ``noise``
        under ``perception`` (default: this bundle's; its TCP noise set to ``noise``) with
        the policies on TCP filter estimates of gain ``filter_gain`` (None: raw)."""
        seen = perception or self.perception
        if seen is not None:
            seen = replace(seen, tcp_noise=float(noise))
        return replace(
            self,
            success_rates={str(k): float(v) for k, v in rates.items()},
            noise=float(noise),
            perception=seen,
            filter_gain=filter_gain,
            rates_from=None,
        )

    def to_manifest(self) -> dict[str, Any]:
        """The manifest: the provenance keys first, then the perception, noise, filter gain
        and success rates."""
        manifest = {k: v for k, v in self.provenance.items() if k not in _OWN_KEYS}
        manifest[PERCEPTION_KEY] = None if self.perception is None else self.perception.to_dict()
        manifest[NOISE_KEY] = self.noise
        manifest[FILTER_KEY] = self.filter_gain
        if self.motion_model is not None:
            manifest[MOTION_KEY] = list(self.motion_model)
        if self.success_rates:
            manifest[RATES_KEY] = dict(self.success_rates)
        if self.rates_from is not None:
            manifest[RATES_FROM_KEY] = self.rates_from
        return manifest

    def write(self) -> Path:
        """Write ``manifest.json`` atomically (the folder is created if missing).

        Raises:
            OutputError: it cannot be written (or lies inside the package); names the path.
        """
        text = json.dumps(self.to_manifest(), indent=2)
        return atomic_write(self.manifest_path, lambda tmp: tmp.write_text(text))

    @classmethod
    def read(cls, directory: str | Path, domain: Domain | None = None) -> ModelBundle:
        """The bundle of a defaults folder (an empty one if it has no manifest).

        Args:
            directory: the folder.
            domain: checks the success rates' skill names against it (rates in [0, 1] are
                checked either way).

        Raises:
            CheckpointError: a corrupt manifest, an unknown skill, a rate outside [0, 1],
                a malformed perception, noise or filter gain; names the file.
        """
        root = Path(directory)
        manifest = read_manifest(root)
        path = root / MANIFEST
        rates = success_rates(manifest, path, domain)
        perception = _perception(manifest.get(PERCEPTION_KEY), path)
        noise = _number(manifest, NOISE_KEY, path)
        if noise is None and perception is not None and manifest.get(RATES_KEY):
            noise = perception.tcp_noise
        return cls(
            directory=root,
            success_rates=rates,
            perception=perception,
            noise=noise,
            filter_gain=_number(manifest, FILTER_KEY, path),
            motion_model=manifest_motion_model(manifest, path),
            rates_from=_text(manifest.get(RATES_FROM_KEY), path),
            provenance={k: v for k, v in manifest.items() if k not in _OWN_KEYS},
        )


def _perception(value: object, path: Path) -> PerceptionSpec | None:
    if value is None:
        return None
    if not isinstance(value, dict):
        raise CheckpointError(f"{path}: {PERCEPTION_KEY!r} must be an object, got {value!r}")
    try:
        return PerceptionSpec(**value)
    except (TypeError, OSGError) as err:
        raise CheckpointError(f"{path}: malformed {PERCEPTION_KEY!r} ({err})") from err


def _number(manifest: dict[str, Any], key: str, path: Path) -> float | None:
    value = manifest.get(key)
    if value is None:
        return None
    if not is_json_number(value) or not math.isfinite(value) or value < 0:
        raise CheckpointError(f"{path}: {key!r} = {value!r} is not a finite number >= 0")
    return float(value)


def _text(value: object, path: Path) -> str | None:
    if value is None or isinstance(value, str):
        return value
    raise CheckpointError(f"{path}: {RATES_FROM_KEY!r} must be text, got {value!r}")


def measured_graph(domain: Domain, directory: str | Path | None = None) -> SkillGraph:
    """The domain's skill graph with the success rates of a defaults directory (default:
    the domain's shipped one; uniform costs when there is none)."""
    root = Path(directory) if directory is not None else domain.defaults_dir
    if root is None:
        return graph_from_specs(domain)
    if not (root / MANIFEST).exists():
        LOGGER.warning(
            "%s: no %s: planning at uniform skill costs (no measured success rates)",
            root,
            MANIFEST,
        )
    return ModelBundle.read(root, domain).graph(domain)


def read_manifest(directory: Path) -> dict[str, Any]:
    """The manifest of a defaults directory as JSON, unchecked (``ModelBundle.read`` checks
    it); empty if the directory has none."""
    path = Path(directory) / MANIFEST
    if not path.exists():
        return {}
    return read_json_object(path, "manifest", CheckpointError)


def success_rates(manifest: dict[str, Any], path: Path, domain: Domain | None) -> dict[str, float]:
    """The manifest's measured success rates, checked: rates in [0, 1], and with a
    ``domain`` its skills only.

    Raises:
        CheckpointError: an unknown skill or a rate that is not a number in [0, 1].
    """
    rates = manifest.get(RATES_KEY, {})
    if not isinstance(rates, dict):
        raise CheckpointError(f"{path}: {RATES_KEY!r} must map skill names to rates")
    checked = {}
    for name, rate in rates.items():
        if domain is not None and name not in domain.skills_by_name:
            raise CheckpointError(f"{path}: {RATES_KEY!r} names unknown skill {name!r}")
        if not is_json_number(rate) or not math.isfinite(rate) or not 0 <= rate <= 1:
            raise CheckpointError(f"{path}: {RATES_KEY!r}[{name!r}] = {rate!r} is not in [0, 1]")
        checked[name] = float(rate)
    return checked


def manifest_motion_model(manifest: dict[str, Any], path: Path) -> tuple[float, float] | None:
    """A manifest's TCP filter motion model (None when it records none).

    Raises:
        CheckpointError: not two finite numbers within ``MOTION_BOUND``; names the file.
    """
    value = manifest.get(MOTION_KEY)
    if value is None:
        return None
    if not isinstance(value, list):
        raise CheckpointError(f"{path}: {MOTION_KEY!r} must be a list, got {value!r}")
    try:
        return check_motion_model(value)
    except ValueError as err:
        raise CheckpointError(f"{path}: {MOTION_KEY!r}: {err}") from None
