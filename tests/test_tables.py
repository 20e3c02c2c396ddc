"""The code behind the headline numbers: Tables I, III, IV/V on tiny real runs (real MuJoCo,
shipped models): shapes, per-cell seeds, aggregation; and the resumable evaluation."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pytest

from osg_control.data.collect import LocalExecutor
from osg_control.domain.registry import get_domain
from osg_control.evaluation import evaluate
from osg_control.evaluation.evaluate import reach_table, task_table
from osg_control.evaluation.resume import (
    CHUNK_JOBS,
    chunk_sha256,
    resumable_map,
    source_fingerprint,
)
from osg_control.evaluation.skill_table import skill_table

KITCHEN = get_domain("kitchen")
KITCHEN_DEFAULTS = KITCHEN.defaults_dir
assert KITCHEN_DEFAULTS is not None


@pytest.mark.slow
def test_skill_table_shape_and_rates() -> None:
    table = skill_table(
        KITCHEN, KITCHEN_DEFAULTS / "skills", [0.0, 0.02], 2, 0, 1, ["grab-cube", "pick-up-cube"]
    )
    assert [row["skill"] for row in table["rows"]] == ["grab-cube", "pick-up-cube"]
    for row in table["rows"]:
        assert len(row["rates"]) == 2
        assert all(rate in (0.0, 0.5, 1.0) for rate in row["rates"])  # 2 episodes per cell
    again = skill_table(
        KITCHEN, KITCHEN_DEFAULTS / "skills", [0.0, 0.02], 2, 0, 1, ["grab-cube", "pick-up-cube"]
    )
    assert again == table  # seeded


def test_reach_table_aggregates_its_rows() -> None:
    table = reach_table(KITCHEN, None, episodes=1, seed=0, workers=1)
    assert len(table["rows"]) == len(KITCHEN.start_regions) == 8
    rates = np.array([row["success"] for row in table["rows"]])
    assert set(rates.tolist()) <= {0.0, 1.0}
    assert table["average"] == pytest.approx(rates.mean())
    nearest = [row["nearest_node_success"] for row in table["rows"]]
    assert table["nearest_node_average"] == pytest.approx(np.mean(nearest))


@pytest.mark.slow
def test_task_table_cells_seeds_and_averages(monkeypatch) -> None:
    seen = []
    original = evaluate.run_task_episode

    def spy(episode):
        seen.append(episode)
        return original(episode)

    monkeypatch.setattr(evaluate, "run_task_episode", spy)
    table = task_table(
        KITCHEN, None, episodes=1, seed=3, workers=1, tasks=["open-door"], replans=[0]
    )
    rates = np.array(table["rates"])
    assert rates.shape == (1, 1, 8)  # budgets x tasks x regions
    assert table["averages"][0][0] == pytest.approx(rates[0, 0].mean())
    assert len(seen) == 8
    assert {e.start.seed for e in seen} == {3}
    assert len({(e.start.cell, e.start.index) for e in seen}) == 8  # one generator per cell
    assert set(rates.ravel().tolist()) <= {0.0, 1.0}  # one episode per cell


def _any(job: object, result: object) -> None:
    """A check that accepts every stored result (these tests are about the chunk files)."""


def _square(x: int) -> int:
    return x * x


def test_resumable_map_keeps_finished_chunks_and_resumes(tmp_path: Path) -> None:
    jobs = list(range(3 * CHUNK_JOBS + 4))
    calls: list[int] = []

    def interrupted(x: int) -> int:
        if x == 2 * CHUNK_JOBS + 1:
            raise KeyboardInterrupt
        calls.append(x)
        return x * x

    with pytest.raises(KeyboardInterrupt):
        resumable_map(LocalExecutor(1), interrupted, jobs, tmp_path, _any)
    assert len(list(tmp_path.glob("chunk-*.json"))) == 2  # the two finished chunks

    calls.clear()

    def counting(x: int) -> int:
        calls.append(x)
        return x * x

    assert resumable_map(LocalExecutor(1), counting, jobs, tmp_path, _any) == [x * x for x in jobs]
    assert calls == jobs[2 * CHUNK_JOBS :]  # only the unfinished episodes ran again
    assert not list(tmp_path.glob("chunk-*.json"))  # cleaned up when complete


def test_the_cache_folder_changes_with_the_code(tmp_path: Path) -> None:
    """An interrupted evaluation resumed after an upgrade starts afresh: the cache folder's
    name carries a hash of the package's sources."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "sub" / "b.py").write_text("y = 2\n")
    before = source_fingerprint.__wrapped__(tmp_path)
    assert source_fingerprint.__wrapped__(tmp_path) == before
    (tmp_path / "sub" / "b.py").write_text("y = 3\n")
    assert source_fingerprint.__wrapped__(tmp_path) != before
    assert len(source_fingerprint()) == 12


def test_resumable_map_discards_foreign_chunks(tmp_path: Path, caplog) -> None:
    jobs = list(range(CHUNK_JOBS))
    resumable_map(LocalExecutor(1), _square, jobs, None, _any)
    with pytest.raises(KeyboardInterrupt):
        resumable_map(LocalExecutor(1), _interrupt_last, jobs + [999], tmp_path, _any)
    (chunk,) = tmp_path.glob("chunk-*.json")
    stored = json.loads(chunk.read_text())
    stored["results"] = [-1] * len(stored["results"])
    stored["keys"][0] = "something else"
    stored["sha256"] = chunk_sha256(stored["keys"], stored["results"])  # a valid foreign file
    chunk.write_text(json.dumps(stored))
    with caplog.at_level(logging.WARNING):
        results = resumable_map(LocalExecutor(1), _square, jobs + [999], tmp_path, _any)
    assert results == [x * x for x in [*jobs, 999]]
    assert "discarded, its jobs are not this chunk's" in caplog.text


def _interrupt_last(x: int) -> int:
    if x == 999:
        raise KeyboardInterrupt
    return x * x


@pytest.mark.slow
def test_evaluate_tasks_resumes_after_an_interrupt(tmp_path: Path, monkeypatch) -> None:
    """An interrupted ``task_table`` keeps its finished episodes; the rerun gives the same
    table as an uninterrupted one and runs only the rest."""
    args = dict(
        domain=KITCHEN, models=None, episodes=2, seed=0, workers=1, tasks=["open-door"], replans=[0]
    )
    clean = task_table(**args)
    original = evaluate.run_task_episode
    ran: list[int] = []

    def flaky(episode):
        if len(ran) == 12:
            raise KeyboardInterrupt
        ran.append(episode.start.index)
        return original(episode)

    monkeypatch.setattr(evaluate, "run_task_episode", flaky)
    with pytest.raises(KeyboardInterrupt):
        task_table(**args, resume_dir=tmp_path)
    ran.clear()
    monkeypatch.setattr(evaluate, "run_task_episode", lambda e: (ran.append(0), original(e))[1])
    resumed = task_table(**args, resume_dir=tmp_path)
    assert resumed == clean
    assert len(ran) == 16 - CHUNK_JOBS  # the first chunk was kept


@pytest.mark.parametrize("index", [0, 1, 2])
def test_one_run_scores_every_replanning_budget_as_its_own_run(index: int) -> None:
    """Tables IV/V run each episode once with the largest budget: the score for budget 0 is
    the score of an episode run with no replanning at all (same seeds, same first attempt),
    under the paper's 2 cm noise, where first attempts fail (episode 0 replans)."""
    from osg_control.perception.spec import PerceptionSpec

    seen = PerceptionSpec("paper", tcp_noise=0.02)
    start = evaluate.StartEpisode("kitchen", "open-pick-up", None, 5, seen, 0, 5, index)
    both = evaluate.run_task_episode(evaluate.TaskEpisode(start, "open-pick-up", (0, 2), 0.2))
    alone = evaluate.run_task_episode(evaluate.TaskEpisode(start, "open-pick-up", (0,), 0.2))
    assert both[0] == alone[0]
    assert both[1][0] >= both[0][0] and both[1][1] >= both[0][1]  # more budget: no less
