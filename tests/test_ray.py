"""The Ray backend on a local Ray instance (2 CPUs): same bytes and tables as the local
pool, every ``--backend`` verb's same results, jobs drawn lazily, a killed worker's chunk
rerun, clear errors when Ray is missing or unreachable. The instance lives in the pytest
process for this module only: the fault tests that start processes of their own
(``test_reliability_parallel``) run without it."""

from __future__ import annotations

import argparse
import functools
import hashlib
import itertools
import json
import operator
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from ports import closed_port

from osg_control.cli import build_parser, main
from osg_control.data.collect import collect_skill
from osg_control.domain.registry import get_domain
from osg_control.errors import BackendError
from osg_control.evaluation.evaluate import task_table
from osg_control.parallel import LocalExecutor, open_executor
from osg_control.parallel.lazy import IN_FLIGHT_PER_WORKER
from osg_control.parallel.ray_backend import RayExecutor

KITCHEN = get_domain("kitchen")

ray = pytest.importorskip("ray")
SKILL = "move-home-to-door"


@pytest.fixture(scope="module")
def ray_executor() -> Iterator[RayExecutor]:
    """One small local Ray instance for the module, shut down after it."""
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        yield RayExecutor()
    finally:
        ray.shutdown()


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _ray_workers_running(function: str) -> list[int]:
    """Processes of this test's Ray instance now running ``function`` (their title)."""
    pids = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                title = (entry / "cmdline").read_bytes().split(b"\0")[0].decode()
            except OSError:
                continue
            if title == f"ray::{function}":
                pids.append(int(entry.name))
    return pids


@pytest.mark.slow
def test_ray_collection_has_the_same_bytes_as_the_local_pool(
    tmp_path: Path, ray_executor: RayExecutor
) -> None:
    local = collect_skill(KITCHEN, SKILL, 6, 3, tmp_path / "local", LocalExecutor(2), False, 2)
    remote = collect_skill(KITCHEN, SKILL, 6, 3, tmp_path / "ray", ray_executor, False, 2)
    assert _sha256(local.path) == _sha256(remote.path)


@pytest.mark.slow
def test_ray_workers_rebuild_another_robots_domain(
    tmp_path: Path, ray_executor: RayExecutor
) -> None:
    """Ray's workers are fresh processes: they find the UR5's kitchen by its ``ref``
    (``kitchen@ur5``), so its collection has the local pool's bytes, not the Panda's."""
    ur5 = KITCHEN.with_robot("ur5")
    local = collect_skill(ur5, SKILL, 2, 3, tmp_path / "local", LocalExecutor(2), False, 1)
    remote = collect_skill(ur5, SKILL, 2, 3, tmp_path / "ray", ray_executor, False, 1)
    panda = collect_skill(KITCHEN, SKILL, 2, 3, tmp_path / "panda", ray_executor, False, 1)
    assert _sha256(local.path) == _sha256(remote.path) != _sha256(panda.path)


@pytest.mark.slow
def test_ray_task_table_equals_the_local_one(ray_executor: RayExecutor) -> None:
    args = (None, 1, 0, 2, ["open-door"], [0])
    local = task_table(KITCHEN, *args, executor=LocalExecutor(2))
    remote = task_table(KITCHEN, *args, executor=ray_executor)
    assert remote == local
    assert len(local["rates"][0][0]) == 8


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_killed_ray_worker_has_its_chunk_rerun(tmp_path: Path, ray_executor: RayExecutor) -> None:
    reference = collect_skill(KITCHEN, SKILL, 12, 4, tmp_path / "ref", LocalExecutor(1), False, 4)
    killed: list[int] = []

    def kill_one_worker() -> None:
        deadline = time.monotonic() + 60
        while not killed and time.monotonic() < deadline:
            running = _ray_workers_running("_run_chunk")
            if running:
                os.kill(running[0], signal.SIGKILL)
                killed.append(running[0])
            time.sleep(0.05)

    killer = threading.Thread(target=kill_one_worker)
    killer.start()
    result = collect_skill(KITCHEN, SKILL, 12, 4, tmp_path / "ray", ray_executor, False, 4)
    killer.join()
    assert killed, "no Ray worker was seen running a chunk"
    assert result.num_episodes == 12
    assert _sha256(result.path) == _sha256(reference.path)


def test_unreachable_ray_address_fails_fast_with_the_address() -> None:
    address = f"127.0.0.1:{closed_port()}"
    started = time.monotonic()
    with pytest.raises(BackendError, match=f"Ray cluster at '{address}' is unreachable"):
        with open_executor("ray", 1, address):
            pass
    assert time.monotonic() - started < 10


def test_cli_reports_an_unreachable_cluster(capsys: pytest.CaptureFixture[str]) -> None:
    address = f"127.0.0.1:{closed_port()}"
    code = main(["collect", "--skill", SKILL, "--episodes", "1", "--backend", "ray",
                 "--address", address])  # fmt: skip
    assert code == 1
    assert "unreachable" in capsys.readouterr().err


def test_malformed_ray_address_is_named() -> None:
    with pytest.raises(BackendError, match="'nowhere' is not HOST:PORT"):
        with open_executor("ray", 1, "nowhere"):
            pass


def test_missing_ray_says_how_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)
    with pytest.raises(BackendError, match=r"pip install 'osg-control\[ray\]'"):
        with open_executor("ray", 1):
            pass


BACKEND_VERBS = {
    "collect": ["collect", "--skill", SKILL, "--episodes", "4"],
    "evaluate tasks": ["evaluate", "tasks", "--episodes", "1", "--task", "open-door",
                       "--replans", "0", "1"],
    "evaluate benchmark": ["--domain", "franka-kitchen", "evaluate", "benchmark",
                           "--episodes", "2"],
    "eval-skills": ["eval-skills", "--episodes", "2", "--skill", SKILL, "--noise", "0", "0.02"],
    "classifier reach": ["classifier", "reach", "--episodes", "1"],
}  # fmt: skip
"""Every verb that takes --backend, with tiny counts (a test checks the list is complete)."""


TRIPLE = functools.partial(operator.mul, 3)
"""A partial (not a plain function), importable by Ray's workers."""


def _backend_verbs(parser: object, words: tuple[str, ...] = ()) -> set[str]:
    """The verbs (space-joined) of ``parser`` that have a ``--backend`` option."""
    found = set()
    for action in getattr(parser, "_actions", []):
        if action.dest == "backend" and words:
            found.add(" ".join(words))
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found |= _backend_verbs(sub, (*words, name))
    return found


def test_the_backend_verb_list_is_complete() -> None:
    assert _backend_verbs(build_parser()) == set(BACKEND_VERBS)


def _run_json(argv: list[str], capsys: pytest.CaptureFixture[str]) -> dict | list:
    code = main([*argv, "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    return json.loads(out)


@pytest.mark.slow
@pytest.mark.parametrize("verb", list(BACKEND_VERBS))
def test_every_backend_verb_gives_the_same_results_on_local_and_ray(
    verb: str, ray_executor: RayExecutor, tmp_path: Path, capsys, monkeypatch
) -> None:
    results = {}
    for backend in ("local", "ray"):
        monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path / backend))  # no shared resume
        argv = [*BACKEND_VERBS[verb], "--backend", backend, "--workers", "2"]
        results[backend] = _run_json(argv, capsys)
    if verb == "collect":  # the data sets, byte for byte
        local, remote = (
            hashlib.sha256(Path(r[0]["path"]).read_bytes()).hexdigest() for r in results.values()
        )
        assert local == remote
    else:
        assert results["ray"] == results["local"]


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["local", "ray"])
def test_jobs_are_drawn_lazily_with_a_bounded_window(
    backend: str, request: pytest.FixtureRequest
) -> None:
    if backend == "ray":
        request.getfixturevalue("ray_executor")
    drawn = itertools.count()
    items = (next(drawn) for _ in itertools.count())  # endless: a job list can't be built
    with open_executor(backend, 2) as executor:
        mapped = executor.map(TRIPLE, items)
        assert [next(mapped) for _ in range(5)] == [3 * x for x in range(5)]
        mapped.close()
    cpus = 2  # the local pool's workers, or the Ray instance's CPUs
    assert next(drawn) <= 5 + IN_FLIGHT_PER_WORKER * cpus
