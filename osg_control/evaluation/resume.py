"""Resumable evaluation: episode results kept in chunk files, so an interrupted table
(Ctrl-C, SIGTERM, a crash) keeps its finished episodes and the same command resumes.

Each chunk of ``CHUNK_JOBS`` jobs is written atomically to ``<dir>/chunk-<hash>.json``
with the keys of its jobs (``repr`` of each job: the cell, its seed and episode index,
models, noise, budget...). A chunk file is used only when its keys are exactly the
chunk's; a foreign or corrupt file is discarded with a warning and recomputed. When every
chunk is done the files are removed. The folder's name carries ``source_fingerprint``, so an
interrupted evaluation resumed after the package's code changed starts afresh instead of
mixing in episodes the old code ran.
"""

from __future__ import annotations

import hashlib
import json
import logging
from collections.abc import Callable, Sequence
from functools import cache, partial
from pathlib import Path
from typing import Any, TypeVar

from osg_control.io_safety import atomic_write
from osg_control.paths import PACKAGE_DIR

CHUNK_JOBS = 10
LOGGER = logging.getLogger(__name__)
T = TypeVar("T")


@cache
def source_fingerprint(root: Path = PACKAGE_DIR) -> str:
    """A short hash of every Python source under ``root`` (paths and contents): the code
    that ran an evaluation's episodes."""
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:12]


def _run_all(fn: Callable[[T], Any], jobs: Sequence[T]) -> list[Any]:
    """Run one chunk's jobs in order (the unit of work handed to the executor)."""
    return [fn(job) for job in jobs]


def _chunk_path(directory: Path, keys: list[str]) -> Path:
    digest = hashlib.sha256("\n".join(keys).encode()).hexdigest()[:20]
    return directory / f"chunk-{digest}.json"


def _read_chunk(path: Path, keys: list[str]) -> list[Any] | None:
    """The results stored for ``keys`` at ``path``; None (and the file removed) if foreign."""
    if not path.exists():
        return None
    try:
        stored = json.loads(path.read_text())
        if stored["keys"] == keys and len(stored["results"]) == len(keys):
            return list(stored["results"])
        reason = "its jobs are not this chunk's"
    except (OSError, ValueError, KeyError, TypeError) as err:
        reason = f"unreadable ({err})"
    LOGGER.warning("%s: discarded, %s; recomputing it", path, reason)
    path.unlink(missing_ok=True)
    return None


def resumable_map(
    mapper: Any, fn: Callable[[T], Any], jobs: Sequence[T], directory: Path | None
) -> list[Any]:
    """``[fn(job) for job in jobs]`` through ``mapper.map`` (a ``TaskExecutor``), resuming
    from and saving to chunk files under ``directory`` (None: no resume)."""
    if directory is None:
        return list(mapper.map(fn, jobs))
    directory = Path(directory)
    chunks = [list(jobs[i : i + CHUNK_JOBS]) for i in range(0, len(jobs), CHUNK_JOBS)]
    keys = [[repr(job) for job in chunk] for chunk in chunks]
    paths = [_chunk_path(directory, k) for k in keys]
    results: list[list[Any] | None] = [_read_chunk(p, k) for p, k in zip(paths, keys, strict=True)]
    todo = [i for i, r in enumerate(results) if r is None]
    done = mapper.map(partial(_run_all, fn), [chunks[i] for i in todo])
    for index, chunk_results in zip(todo, done, strict=True):
        payload = json.dumps({"keys": keys[index], "results": chunk_results})
        atomic_write(paths[index], partial(Path.write_text, data=payload))
        results[index] = chunk_results
    for path in paths:
        path.unlink(missing_ok=True)
    return [result for chunk_results in results for result in chunk_results or []]
