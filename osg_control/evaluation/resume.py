"""Resumable evaluation: episode results kept in chunk files, so an interrupted table
(Ctrl-C, SIGTERM, a crash) keeps its finished episodes and the same command resumes.

Each chunk of ``CHUNK_JOBS`` jobs is written atomically to ``<dir>/chunk-<hash>.json``
with the keys of its jobs (``repr`` of each job: the cell, its seed and episode index,
models, noise, budget...), their results and the sha256 of both (``chunk_sha256``). A
chunk file is used only when its checksum matches, its keys are exactly the chunk's and
every result passes the caller's ``check`` (an episode's success in {0, 1}, counts
non-negative integers, ...): a foreign, edited, corrupt or impossible file is discarded
with a warning naming the file and why, and recomputed. When every chunk is done the files
are removed. The folder's name carries ``source_fingerprint``, so an
interrupted evaluation resumed after the package's code changed starts afresh instead of
mixing in episodes the old code ran. Chunks are made, checked and submitted one by one as
the work goes (``resumable_results``): memory does not grow with the number of jobs.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import closing
from functools import cache, partial
from itertools import tee
from pathlib import Path
from typing import Any, TypeVar

from osg_control.io_safety import atomic_write
from osg_control.json_files import JSONFormatError, is_json_number, load_json
from osg_control.paths import PACKAGE_DIR

CHUNK_JOBS = 10
LOGGER = logging.getLogger(__name__)
T = TypeVar("T")
Check = Callable[[Any, Any], None]
"""``check(job, result)``: raises ``ValueError`` (or ``TypeError``) saying why a stored
result cannot be the job's (a success of 7.0, a string, a negative count...)."""


@cache
def source_fingerprint(root: Path = PACKAGE_DIR) -> str:
    """A short hash of every Python source under ``root`` (paths and contents): the code
    that ran an evaluation's episodes."""
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:12]


def stored_flag(value: Any, name: str) -> float:
    """A stored 0/1 outcome (a success): exactly 0 or 1, as a JSON number.

    Raises:
        ValueError: anything else (7.0, 0.5, NaN, a string, ``true``), naming ``name``.
    """
    if not is_json_number(value) or value not in (0, 1):
        raise ValueError(f"{name} must be 0 or 1, got {value!r}")
    return float(value)


def stored_count(value: Any, name: str) -> int:
    """A stored count (steps, skills run): a non-negative whole JSON number.

    Raises:
        ValueError: anything else (negative, fractional, NaN, inf, a string), naming ``name``.
    """
    if not (is_json_number(value) and math.isfinite(value) and value >= 0 and value % 1 == 0):
        raise ValueError(f"{name} must be a non-negative whole number, got {value!r}")
    return int(value)


def _run_all(fn: Callable[[T], Any], jobs: Sequence[T]) -> list[Any]:
    """Run one chunk's jobs in order (the unit of work handed to the executor)."""
    return [fn(job) for job in jobs]


def _chunk_path(directory: Path, keys: list[str]) -> Path:
    digest = hashlib.sha256("\n".join(keys).encode()).hexdigest()[:20]
    return directory / f"chunk-{digest}.json"


def chunk_sha256(keys: Any, results: Any) -> str:
    """The checksum a chunk file stores: the sha256 of its keys and results as canonical
    JSON (so any edit of a value, a flipped 0.0 -> 1.0 included, changes it)."""
    text = json.dumps({"keys": keys, "results": results}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _chunk_problem(stored: Any, keys: list[str], jobs: Sequence[Any], check: Check) -> str | None:
    """Why ``stored`` (a chunk file's JSON) is not the results of ``jobs``; None if it is."""
    if not isinstance(stored, dict) or not {"keys", "results", "sha256"} <= stored.keys():
        return "not a chunk of this version (no keys, results and sha256)"
    if stored["sha256"] != chunk_sha256(stored["keys"], stored["results"]):
        return "its content does not match its sha256 checksum (edited or corrupt)"
    if stored["keys"] != keys:
        return "its jobs are not this chunk's"
    results = stored["results"]
    if not isinstance(results, list) or len(results) != len(keys):
        return f"{len(keys)} results expected"
    for i, (job, result) in enumerate(zip(jobs, results, strict=True)):
        try:
            check(job, result)
        except (ValueError, TypeError) as err:
            return f"result {i + 1} is impossible ({err})"
    return None


def _read_chunk(path: Path, keys: list[str], jobs: Sequence[Any], check: Check) -> list[Any] | None:
    """The results stored for ``keys`` at ``path``; None (and the file removed) if the file
    is foreign, edited, corrupt or holds an impossible result."""
    if not path.exists():
        return None
    try:
        stored = load_json(path)
        reason = _chunk_problem(stored, keys, jobs, check)
        if reason is None:
            return list(stored["results"])
    except (OSError, JSONFormatError) as err:
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
    mapper: Any, fn: Callable[[T], Any], jobs: Sequence[T], directory: Path | None, check: Check
) -> Iterator[Any]:
    """``fn(job)`` for each job, in order, through ``mapper.map`` (a ``TaskExecutor``),
    resuming from and saving to chunk files under ``directory`` (None: no resume); a stored
    result is used only if ``check(job, result)`` accepts it.

    ``jobs`` may be a lazy sequence (``parallel.lazy.Jobs``): it is walked once for the
    work and once more, at the end, to remove the chunk files.
    """
    if directory is None:
        yield from mapper.map(fn, jobs)
        return
    directory = Path(directory)
    stored = (
        (path, keys, chunk, _read_chunk(path, keys, chunk, check))
        for path, keys, chunk in _chunks(jobs, directory)
    )
    stream, ahead = tee(stored)
    todo = (chunk for _path, _keys, chunk, results in ahead if results is None)
    with closing(mapper.map(partial(_run_all, fn), todo)) as done:
        for path, keys, _chunk, kept in stream:
            results = next(done) if kept is None else kept
            if kept is None:
                payload = json.dumps(
                    {"keys": keys, "results": results, "sha256": chunk_sha256(keys, results)}
                )
                atomic_write(path, partial(Path.write_text, data=payload))
            yield from results
    for path, _keys, _chunk in _chunks(jobs, directory):
        path.unlink(missing_ok=True)


def resumable_map(
    mapper: Any, fn: Callable[[T], Any], jobs: Sequence[T], directory: Path | None, check: Check
) -> list[Any]:
    """``resumable_results`` as a list."""
    return list(resumable_results(mapper, fn, jobs, directory, check))
