"""A domain's trained defaults (skills + classifier + measured success rates), and their loader.

A defaults directory holds ``skills/`` (one checkpoint per skill), ``classifier/`` and
``manifest.json`` (the command, seeds, data-set hashes and package version that produced
them, and ``success_rates``: each skill's measured Table I rate at the deployment noise,
which become the plan costs), read and checked by ``execution.bundle.ModelBundle``. A
domain ships one (``Domain.defaults_dir``); ``osg reproduce`` writes a directory of the
same layout.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from osg_control.classifier.data import movement_classes
from osg_control.classifier.model import StateClassifier
from osg_control.control.estimator import MOTION_MODEL
from osg_control.domain.base import Domain
from osg_control.errors import CheckpointError
from osg_control.execution.bundle import CLASSIFIER_DIR, MANIFEST, SKILLS_DIR, ModelBundle
from osg_control.learning.checkpoints import check_action_scale, checkpoint_paths, require_skills
from osg_control.learning.policy import SkillPolicy
from osg_control.planning.graph import SkillGraph

__all__ = [
    "Defaults",
    "defaults_root",
    "load_defaults",
    "load_skill_policies",
]


@dataclass(frozen=True)
class Defaults:
    """What a defaults directory holds, loaded.

    Attributes:
        directory: where it was read from.
        policies: skill name -> policy.
        classifier: the state->skill classifier.
        graph: the domain's skill graph with the manifest's success rates (uniform costs
            for skills without one).
        bundle: the manifest, read and checked (``execution.bundle.ModelBundle``).
        motion_model: the TCP filter's ``(k_now, k_prev)`` fitted on the defaults' data
            (the manifest's ``motion_model``; ``control.estimator.MOTION_MODEL`` when it
            records none).
    """

    directory: Path
    policies: dict[str, SkillPolicy]
    classifier: StateClassifier
    graph: SkillGraph
    bundle: ModelBundle
    motion_model: tuple[float, float] = MOTION_MODEL


def defaults_root(domain: Domain, directory: str | Path | None = None) -> Path:
    """The defaults directory to use: ``directory``, else the domain's shipped one.

    Raises:
        CheckpointError: the domain ships none and no directory is given.
    """
    if directory is not None:
        return Path(directory)
    if domain.defaults_dir is None:
        raise CheckpointError(f"domain {domain.name!r} ships no defaults; pass a directory")
    return domain.defaults_dir


def load_defaults(domain: Domain, directory: str | Path | None = None) -> Defaults:
    """Load skill policies, the classifier and the success rates of a defaults directory.

    Raises:
        CheckpointError: a missing or corrupt checkpoint or manifest, named.
    """
    root = defaults_root(domain, directory)
    if not root.is_dir():
        raise CheckpointError(f"{root}: defaults directory not found")
    bundle = ModelBundle.read(root, domain)
    return Defaults(
        directory=root,
        policies=load_skill_policies(domain, bundle.policies_dir),
        classifier=StateClassifier.load(bundle.classifier_dir, movement_classes(domain)),
        graph=bundle.graph(domain),
        bundle=bundle,
        motion_model=bundle.motion_model or MOTION_MODEL,
    )


def load_skill_policies(
    domain: Domain, directory: str | Path, names: Sequence[str] | None = None
) -> dict[str, SkillPolicy]:
    """The policies of ``names`` (default: every skill of the domain) from a skill
    checkpoint folder, each checked against the domain.

    Raises:
        CheckpointError: the folder lacks skills (all of them named), or a checkpoint is
            missing, corrupt, another skill's, or its ``action_scale`` is not the domain's
            ``action_bounds`` (the file named).
    """
    names = list(domain.skills_by_name if names is None else names)
    require_skills(directory, names)
    policies = {name: SkillPolicy.load(directory, name) for name in names}
    for name, policy in policies.items():
        sidecar = checkpoint_paths(directory, name)[1]
        check_action_scale(sidecar, policy.checkpoint.action_scale, domain.action_bounds)
    return policies


def models_in_use(domain: Domain, directory: str | Path | None = None) -> dict[str, str]:
    """Which skill and classifier checkpoints a command loads (for its output and --json)."""
    root = defaults_root(domain, directory)
    shipped = domain.defaults_dir is not None and root.resolve() == domain.defaults_dir.resolve()
    return {
        "domain": domain.name,
        "directory": str(root),
        "source": "shipped defaults" if shipped else "given --models",
        "skills": str(root / SKILLS_DIR),
        "classifier": str(root / CLASSIFIER_DIR),
    }


def describe_models(models: dict[str, str]) -> str:
    """One line naming the models of ``models_in_use``."""
    return f"models: {models['directory']} ({models['source']})"


def models_fingerprint(domain: Domain, directory: str | Path | None = None) -> str:
    """A short hash of a defaults folder's sidecars (which record their weights' sha256) and
    manifest (its success rates set the plan costs): results computed with other models
    never match it."""
    root = defaults_root(domain, directory)
    digest = hashlib.sha256(domain.name.encode())
    for path in sorted([*root.glob("*/*.json"), *root.glob(MANIFEST)]):
        digest.update(path.name.encode() + path.read_bytes())
    return digest.hexdigest()[:16]
