"""Trust checks for the chunk files of a resumable collection.

A chunk is merged only if it is the chunk its name claims: a readable, valid data set
(``load_dataset``: every field's values checked) whose every array carries its sha256
checksum and matches it, of the same skill spec, seed and episode range, in this format. A file
that fails is discarded with a warning and recomputed, never merged.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

from osg_control.data.datasets import FORMAT_VERSION, load_dataset
from osg_control.errors import DatasetError
from osg_control.json_files import parse_json

LOGGER = logging.getLogger(__name__)


def chunk_attrs(skill_json: str, seed: int, start: int, stop: int) -> dict[str, Any]:
    """The attributes that identify a chunk (written into it, checked on resume)."""
    return {"skill": skill_json, "seed": seed, "chunk_start": start, "chunk_stop": stop}


def chunk_mismatch(path: Path, expected: dict[str, Any]) -> str | None:
    """Why the file at ``path`` is not the chunk ``expected`` describes; None if it is."""
    try:
        dataset = load_dataset(path, require_checksums=True)
    except DatasetError as err:
        return str(err)
    attrs = dataset.attrs
    if int(attrs.get("format_version", -1)) != FORMAT_VERSION:
        return f"format version {attrs.get('format_version')}, expected {FORMAT_VERSION}"
    if parse_json(attrs["skill"]) != parse_json(expected["skill"]):
        return f"recorded for skill {dataset.skill_name!r} with another spec"
    for key in ("seed", "chunk_start", "chunk_stop"):
        if key not in attrs or int(attrs[key]) != int(expected[key]):
            return f"{key} {attrs.get(key)}, expected {expected[key]}"
    episodes = int(expected["chunk_stop"]) - int(expected["chunk_start"])
    if dataset.num_episodes != episodes:
        return f"{dataset.num_episodes} episodes, expected {episodes}"
    return None


def keep_chunk(path: Path, expected: dict[str, Any]) -> bool:
    """Whether an existing chunk file can be merged; a foreign one is removed (warned)."""
    if not path.exists():
        return False
    reason = chunk_mismatch(path, expected)
    if reason is None:
        return True
    LOGGER.warning("%s: discarded, not the expected chunk (%s); recomputing it", path, reason)
    path.unlink()
    return False
