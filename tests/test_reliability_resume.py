"""Reliability, round 4: a resumed evaluation never trusts a kept chunk. Every resumable
chunk kind (Tables IV/V's task episodes, the benchmark's episodes, collection chunks) is
checked on read; an edited, corrupt or impossible chunk is discarded with a warning naming
the file and why, and recomputed, so the final result equals an uninterrupted run's."""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from osg_control.domain.registry import get_domain
from osg_control.evaluation import evaluate
from osg_control.evaluation.benchmark import BenchmarkEpisode, check_benchmark_result
from osg_control.evaluation.evaluate import check_task_result, task_table
from osg_control.evaluation.resume import CHUNK_JOBS, chunk_sha256, resumable_map
from osg_control.parallel.local import LocalExecutor

KITCHEN = get_domain("kitchen")
ARGS: dict[str, Any] = dict(
    domain=KITCHEN, models=None, episodes=2, seed=0, workers=1, tasks=["open-door"], replans=[0, 2]
)
JOBS = 16  # 8 start regions x 2 episodes


def _edit(change: Callable[[dict[str, Any]], Any], reseal: bool = False) -> Callable[[str], str]:
    """An edit of a chunk file's JSON: ``change`` applied to the parsed file, the checksum
    updated to match when ``reseal`` (a forger who knows the format)."""

    def edit(text: str) -> str:
        stored = json.loads(text)
        change(stored)
        if reseal:
            stored["sha256"] = chunk_sha256(stored["keys"], stored["results"])
        return json.dumps(stored)

    return edit


def _set_success(value: Any) -> Callable[[dict[str, Any]], Any]:
    def change(stored: dict[str, Any]) -> None:
        stored["results"][0][0][0] = value

    return change


def _flip(stored: dict[str, Any]) -> None:
    """The first success of the chunk flipped (0.0 -> 1.0, or 1.0 -> 0.0)."""
    stored["results"][0][0][0] = 1.0 - stored["results"][0][0][0]


def _drop_checksum(stored: dict[str, Any]) -> None:
    del stored["sha256"]


def _set_count(value: Any) -> Callable[[dict[str, Any]], Any]:
    def change(stored: dict[str, Any]) -> None:
        stored["results"][0][1][1] = value

    return change


EDITS: list[tuple[str, Callable[[str], str], str]] = [
    ("success 7.0", _edit(_set_success(7.0), reseal=True), "success must be 0 or 1, got 7.0"),
    ("success 0.5", _edit(_set_success(0.5), reseal=True), "success must be 0 or 1, got 0.5"),
    ("flipped, checksum kept", _edit(_flip), "does not match its sha256"),
    ("success a string", _edit(_set_success("1.0"), reseal=True), "success must be 0 or 1"),
    ("success true", _edit(_set_success(True), reseal=True), "success must be 0 or 1"),
    ("success NaN", _edit(_set_success(math.nan), reseal=True), "NaN is not a JSON number"),
    ("truncated", lambda text: text[: len(text) // 2], "unreadable"),
    ("not UTF-8", lambda text: "\udcff" + text, "unreadable"),
    ("checksum missing", _edit(_drop_checksum), "not a chunk of this version"),
    ("count -1", _edit(_set_count(-1.0), reseal=True), "skills run must be a non-negative"),
    ("count 2.5", _edit(_set_count(2.5), reseal=True), "skills run must be a non-negative"),
    ("count falls", _edit(_set_count(0.0), reseal=True), "skills run fall as the budget grows"),
    ("one budget", _edit(lambda s: s["results"][0].pop(), reseal=True), "expected 2 budgets"),
    ("a result short", _edit(lambda s: s["results"].pop(), reseal=True), "10 results expected"),
    ("not an object", lambda text: "[1, 2]", "not a chunk of this version"),
]


@pytest.fixture(scope="module")
def interrupted(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """An uninterrupted table, every episode's result (to replay them: episodes are
    deterministic), and the chunk file an interrupted run kept."""
    results: dict[tuple[int, int], Any] = {}
    original = evaluate.run_task_episode

    def recording(episode: evaluate.TaskEpisode) -> Any:
        result = original(episode)
        results[episode.start.cell, episode.start.index] = result
        return result

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(evaluate, "run_task_episode", recording)
        clean = task_table(**ARGS)
    folder = tmp_path_factory.mktemp("chunks")

    def stopping(episode: evaluate.TaskEpisode) -> Any:
        if episode.start.cell == 5:  # after the first chunk of ten
            raise KeyboardInterrupt
        return results[episode.start.cell, episode.start.index]

    with pytest.MonkeyPatch.context() as patch, pytest.raises(KeyboardInterrupt):
        patch.setattr(evaluate, "run_task_episode", stopping)
        task_table(**ARGS, resume_dir=folder)
    (chunk,) = folder.glob("chunk-*.json")
    return {"clean": clean, "results": results, "chunk": chunk.name, "text": chunk.read_text()}


def _resume(
    interrupted: dict[str, Any], folder: Path, monkeypatch: pytest.MonkeyPatch
) -> tuple[dict[str, Any], int]:
    """Resume from ``folder`` replaying the recorded episodes; the table and how many ran."""
    ran: list[int] = []

    def replay(episode: evaluate.TaskEpisode) -> Any:
        ran.append(1)
        return interrupted["results"][episode.start.cell, episode.start.index]

    monkeypatch.setattr(evaluate, "run_task_episode", replay)
    return task_table(**ARGS, resume_dir=folder), len(ran)


def test_an_intact_chunk_is_kept(
    interrupted: dict[str, Any], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / interrupted["chunk"]).write_text(interrupted["text"])
    table, ran = _resume(interrupted, tmp_path, monkeypatch)
    assert table == interrupted["clean"] and ran == JOBS - CHUNK_JOBS


@pytest.mark.parametrize(("name", "edit", "reason"), EDITS, ids=[e[0] for e in EDITS])
def test_an_edited_or_corrupt_task_chunk_is_discarded_and_recomputed(
    name: str,
    edit: Callable[[str], str],
    reason: str,
    interrupted: dict[str, Any],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
) -> None:
    chunk = tmp_path / interrupted["chunk"]
    chunk.write_text(edit(interrupted["text"]), encoding="utf-8", errors="surrogateescape")
    with caplog.at_level(logging.WARNING):
        table, ran = _resume(interrupted, tmp_path, monkeypatch)
    assert ran == JOBS  # the edited chunk was recomputed, not trusted
    assert table == interrupted["clean"]
    assert f"{chunk}: discarded" in caplog.text and reason in caplog.text


BENCH_JOB = BenchmarkEpisode("franka-kitchen", None, "set", ("kettle", "microwave"), 0, 0)
GOOD = {"completed": ["kettle"], "steps": 120, "failure": None}


@pytest.mark.parametrize(
    ("result", "reason"),
    [
        ({**GOOD, "steps": -1}, "steps must be a non-negative"),
        ({**GOOD, "steps": math.nan}, "steps must be a non-negative"),
        ({**GOOD, "steps": "120"}, "steps must be a non-negative"),
        ({**GOOD, "completed": ["bogus"]}, "completed must be distinct tasks"),
        ({**GOOD, "completed": ["kettle", "kettle"]}, "completed must be distinct tasks"),
        ({**GOOD, "completed": "kettle"}, "completed must be a list"),
        ({**GOOD, "failure": 3}, "failure must be null or text"),
        ({"completed": ["kettle"], "steps": 1}, "expected completed, steps and failure"),
        ([1], "expected completed, steps and failure"),
    ],
)
def test_impossible_benchmark_results_are_refused(result: Any, reason: str) -> None:
    check_benchmark_result(BENCH_JOB, GOOD)  # the good one passes
    with pytest.raises(ValueError, match=reason):
        check_benchmark_result(BENCH_JOB, result)


@pytest.mark.parametrize(
    ("result", "reason"),
    [
        ([[1.0, 3.0], [1.0, 3.0]], None),
        ([[0.0, 2.0], [1.0, 5.0]], None),
        ([[7.0, 3.0], [1.0, 3.0]], "replans=0 success must be 0 or 1"),
        ([[1.0, 3.0], [1.0, math.inf]], "replans=2 skills run must be"),
        ([[1.0, 3.0], "x"], "replans=2: expected \\[success, skills run\\]"),
        ([[1.0, 3.0]], "expected 2 budgets"),
    ],
)
def test_impossible_task_results_are_refused(result: Any, reason: str | None) -> None:
    episode = evaluate.TaskEpisode(None, "open-door", (0, 2))  # type: ignore[arg-type]
    if reason is None:
        check_task_result(episode, result)
    else:
        with pytest.raises(ValueError, match=reason):
            check_task_result(episode, result)


def _benchmark_result(job: int) -> dict[str, Any]:
    return {"completed": ["kettle"] if job % 2 else [], "steps": 100 + job, "failure": None}


def test_an_impossible_benchmark_chunk_is_recomputed(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """The benchmark's chunks go through the same read: a resealed impossible value is
    refused by its check, recomputed, and the results equal an uninterrupted run's."""
    jobs = list(range(CHUNK_JOBS))

    def check(job: int, result: Any) -> None:
        check_benchmark_result(BENCH_JOB, result)

    clean = resumable_map(LocalExecutor(1), _benchmark_result, jobs, tmp_path, check)
    assert not list(tmp_path.iterdir())  # removed when complete
    stored = {"keys": [repr(j) for j in jobs], "results": clean}
    stored["results"] = [dict(r) for r in clean]
    stored["results"][3]["steps"] = -5
    stored["sha256"] = chunk_sha256(stored["keys"], stored["results"])
    ran: list[int] = []

    def counting(job: int) -> dict[str, Any]:
        ran.append(job)
        return _benchmark_result(job)

    with pytest.raises(KeyboardInterrupt):  # write the chunk where the run will look
        resumable_map(LocalExecutor(1), _interrupt, [*jobs, 99], tmp_path, check)
    (chunk,) = tmp_path.glob("chunk-*.json")
    chunk.write_text(json.dumps(stored))
    with caplog.at_level(logging.WARNING):
        again = resumable_map(LocalExecutor(1), counting, [*jobs, 99], tmp_path, check)
    assert again[:CHUNK_JOBS] == clean and ran == [*jobs, 99]
    assert "result 4 is impossible (steps must be a non-negative whole number" in caplog.text


def _interrupt(job: int) -> dict[str, Any]:
    if job == 99:
        raise KeyboardInterrupt
    return _benchmark_result(job)
