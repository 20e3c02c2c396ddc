"""Reliability, round 4: a sidecar's normalisation is covered by a checksum. The weights'
sha256 never covered a skill's ``obs_mean``/``obs_std``/``action_scale`` or the
classifier's normalisation: an edited value loaded and the skill's success dropped to 0
without a word. Each edit below is a named ``CheckpointError``; files from before the
checksum (skill format 1, a classifier sidecar without it) still load."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from osg_control.classifier.model import SIDECAR_FILE, StateClassifier
from osg_control.errors import CheckpointError
from osg_control.learning.checkpoints import load_checkpoint

SHIPPED = Path(__file__).resolve().parents[1] / "osg_control/kitchen/defaults"
SKILL = "grab-cube"


def _nudge(key: str, index: int = 0) -> Callable[[dict[str, Any]], None]:
    def edit(sidecar: dict[str, Any]) -> None:
        sidecar[key][index] = sidecar[key][index] * 1.5 + 0.01

    return edit


def _legacy(sidecar: dict[str, Any]) -> None:
    sidecar["format_version"] = 1
    del sidecar["normalisation_sha256"]


SKILL_EDITS: list[tuple[str, Callable[[dict[str, Any]], None], str | None]] = [
    ("obs_mean edited", _nudge("obs_mean"), "obs_mean, obs_std, action_scale do not match"),
    ("obs_std edited", _nudge("obs_std", 3), "do not match the sidecar's normalisation_sha256"),
    ("action_scale edited", _nudge("action_scale", 6), "normalisation_sha256"),
    ("checksum removed", lambda s: s.pop("normalisation_sha256"), "lacks normalisation_sha256"),
    ("checksum wrong", lambda s: s.update(normalisation_sha256="0" * 64), "do not match"),
    ("format 1 without it", _legacy, None),
]


@pytest.mark.parametrize(("case", "edit", "fragment"), SKILL_EDITS, ids=[e[0] for e in SKILL_EDITS])
def test_an_edited_skill_normalisation_is_refused(
    case: str, edit: Callable[[dict[str, Any]], None], fragment: str | None, tmp_path: Path
) -> None:
    for suffix in (".json", ".safetensors"):
        shutil.copy(SHIPPED / "skills" / f"{SKILL}{suffix}", tmp_path)
    sidecar = tmp_path / f"{SKILL}.json"
    data = json.loads(sidecar.read_text())
    edit(data)
    sidecar.write_text(json.dumps(data))
    if fragment is None:
        assert load_checkpoint(tmp_path, SKILL).skill.name == SKILL  # legacy: loads
        return
    with pytest.raises(CheckpointError) as raised:
        load_checkpoint(tmp_path, SKILL)
    assert str(raised.value).startswith(str(sidecar)) and fragment in str(raised.value), case


@pytest.mark.parametrize("which", ["mean", "std"])
def test_an_edited_classifier_normalisation_is_refused(which: str, tmp_path: Path) -> None:
    folder = shutil.copytree(SHIPPED / "classifier", tmp_path / "classifier")
    sidecar = folder / SIDECAR_FILE
    data = json.loads(sidecar.read_text())
    data["normalisation"][which][0] += 0.5
    sidecar.write_text(json.dumps(data))
    with pytest.raises(CheckpointError, match="normalisation mean and std do not match"):
        StateClassifier.load(folder)
    del data["normalisation_sha256"]  # a sidecar from before the checksum still loads
    sidecar.write_text(json.dumps(data))
    assert StateClassifier.load(folder).classes


def test_a_saved_classifier_round_trips_with_its_checksum(tmp_path: Path) -> None:
    model = StateClassifier.load(SHIPPED / "classifier")
    model.save(tmp_path)
    assert "normalisation_sha256" in json.loads((tmp_path / SIDECAR_FILE).read_text())
    assert StateClassifier.load(tmp_path).classes == model.classes
