"""Resumable evaluation: episode results kept in chunk files, so an interrupted table
(Ctrl-C, SIGTERM, a crash) keeps its finished episodes and the same command resumes.

Each chunk of ``CHUNK_JOBS`` jobs is written atomically to ``<dir>/chunk-<hash>.json``
with the keys of its jobs (``repr`` of each job: the cell, its seed and episode index,
models, noise, budget...). A chunk file is used only when its keys are exactly the
chunk's; a foreign or corrupt file is discarded with a warning and recomputed. When every
chunk is done the files are removed. The folder's name carries ``source_fingerprint``, so an
interrupted evaluation resumed after the package's code changed starts afresh instead of
mixing in episodes the old code ran. Chunks are made, checked and submitted one by one as
the work goes (``resumable_results``): memory does not grow with the number of jobs.
"""

from __future__ import annotations

import hashlib
import json
import logging
from collections.abc import Callable, Iterator, Sequence
from contextlib import closing
from functools import cache, partial
from itertools import tee
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


def _chunks(jobs: Sequence[T], directory: Path) -> Iterator[tuple[Path, list[str], list[T]]]:
    """Each chunk's file, keys and jobs, made as they are asked for."""
    for start in range(0, len(jobs), CHUNK_JOBS):
        chunk = list(jobs[start : start + CHUNK_JOBS])
        keys = [repr(job) for job in chunk]
        yield _chunk_path(directory, keys), keys, chunk


def resumable_results(
    mapper: Any, fn: Callable[[T], Any], jobs: Sequence[T], directory: Path | None
) -> Iterator[Any]:
    """``fn(job)`` for each job, in order, through ``mapper.map`` (a ``TaskExecutor``),
    resuming from and saving to chunk files under ``directory`` (None: no resume).

    ``jobs`` may be a lazy sequence (``parallel.lazy.Jobs``): it is walked once for the
    work and once more, at the end, to remove the chunk files.
    """
    if directory is None:
        yield from mapper.map(fn, jobs)
        return
    directory = Path(directory)
    stored = (
        (path, keys, chunk, _read_chunk(path, keys))
        for path, keys, chunk in _chunks(jobs, directory)
    )
    stream, ahead = tee(stored)
    todo = (chunk for _path, _keys, chunk, results in ahead if results is None)
    with closing(mapper.map(partial(_run_all, fn), todo)) as done:
        for path, keys, _chunk, kept in stream:
            results = next(done) if kept is None else kept
            if kept is None:
                payload = json.dumps({"keys": keys, "results": results})
                atomic_write(path, partial(Path.write_text, data=payload))
            yield from results
    for path, _keys, _chunk in _chunks(jobs, directory):
        path.unlink(missing_ok=True)


def resumable_map(
    mapper: Any, fn: Callable[[T], Any], jobs: Sequence[T], directory: Path | None
) -> list[Any]:
    """``resumable_results`` as a list."""
    return list(resumable_results(mapper, fn, jobs, directory))
