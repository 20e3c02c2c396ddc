"""The trained defaults shipped inside the package (skills + classifier), and their loader.

``osg_control/defaults/`` holds ``skills/`` (one checkpoint per skill), ``classifier/`` and
``manifest.json`` (the command, seeds, data-set hashes and package version that produced
them). ``osg reproduce`` writes a directory of the same layout.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from osg_control.classifier.model import StateClassifier
from osg_control.errors import CheckpointError
from osg_control.learning.policy import SkillPolicy, load_policies
from osg_control.paths import DEFAULTS_DIR

MANIFEST = "manifest.json"


def load_defaults(
    directory: str | Path | None = None,
) -> tuple[dict[str, SkillPolicy], StateClassifier]:
    """Load skill policies and the classifier from ``directory`` (default: the shipped ones).

    Raises:
        CheckpointError: a missing or corrupt checkpoint, named.
    """
    root = Path(directory) if directory is not None else DEFAULTS_DIR
    if not root.is_dir():
        raise CheckpointError(f"{root}: defaults directory not found")
    return load_policies(root / "skills"), StateClassifier.load(root / "classifier")


def read_manifest(directory: str | Path | None = None) -> dict[str, Any]:
    """The manifest of a defaults directory (how its checkpoints were made)."""
    path = (Path(directory) if directory is not None else DEFAULTS_DIR) / MANIFEST
    try:
        return dict(json.loads(path.read_text()))
    except (OSError, ValueError) as err:
        raise CheckpointError(f"{path}: unreadable manifest ({err})") from err


def models_in_use(directory: str | Path | None = None) -> dict[str, str]:
    """Which skill and classifier checkpoints a command loads (for its output and --json)."""
    root = Path(directory) if directory is not None else DEFAULTS_DIR
    shipped = root.resolve() == DEFAULTS_DIR.resolve()
    return {
        "directory": str(root),
        "source": "shipped defaults" if shipped else "given --models",
        "skills": str(root / "skills"),
        "classifier": str(root / "classifier"),
    }


def describe_models(models: dict[str, str]) -> str:
    """One line naming the models of ``models_in_use``."""
    return f"models: {models['directory']} ({models['source']})"


def models_fingerprint(directory: str | Path | None = None) -> str:
    """A short hash of a defaults folder's sidecars (which record their weights' sha256):
    results computed with other models never match it."""
    root = Path(directory) if directory is not None else DEFAULTS_DIR
    digest = hashlib.sha256()
    for path in sorted(root.glob("*/*.json")):
        digest.update(path.name.encode() + path.read_bytes())
    return digest.hexdigest()[:16]
