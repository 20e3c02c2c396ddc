"""Executor backends without Ray: backend names, and local pool workers dying with osg."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from osg_control.cli import main
from osg_control.commands.errors import handle_errors
from osg_control.errors import EXIT_CODES, BackendError
from osg_control.parallel import LocalExecutor, open_executor
from osg_control.parallel.lazy import INTERRUPTED, windowed
from osg_control.parallel.processes import descendants, process_stat

ROOT = Path(__file__).resolve().parents[1]


def _square(x: int) -> int:
    return x * x


def _children(pid: int) -> list[int]:
    """Every live descendant of ``pid``."""
    return [child for child, _start in descendants(pid)]


def _alive(pid: int) -> bool:
    stat = process_stat(pid)
    return stat is not None and stat.state != "Z"


def test_local_pool_returns_results_in_order() -> None:
    assert list(LocalExecutor(2).map(_square, range(7))) == [x * x for x in range(7)]


def test_local_pool_results_stay_in_order_over_a_lazy_list() -> None:
    assert list(LocalExecutor(2).map(_square, iter(range(50)))) == [x * x for x in range(50)]


def test_unknown_backend_lists_the_known_ones() -> None:
    with pytest.raises(BackendError, match="unknown backend 'dask'; known backends: local, ray"):
        with open_executor("dask", 1):
            pass


def test_address_without_ray_backend_is_refused() -> None:
    with pytest.raises(BackendError, match="--address needs --backend ray"):
        with open_executor("local", 1, "127.0.0.1:6379"):
            pass


def test_cli_rejects_an_unknown_backend(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["collect", "--backend", "dask"])
    assert "choose from 'local', 'ray'" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_pool_workers_exit_when_osg_collect_is_killed(tmp_path: Path, sig: int) -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OSG_CACHE_DIR": str(tmp_path)}
    command = [sys.executable, "-m", "osg_control.cli", "collect", "--skill", "move-home-to-door"]
    command += ["--episodes", "400", "--workers", "2", "--out", str(tmp_path), "--json"]
    parent = subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL)
    workers: list[int] = []
    try:
        deadline = time.monotonic() + 60
        while len(workers) < 2 and time.monotonic() < deadline:
            time.sleep(0.2)
            workers = _children(parent.pid)
        assert len(workers) >= 2, "the pool never started"
        parent.send_signal(sig)
        parent.wait(timeout=10)
        deadline = time.monotonic() + 10
        while any(map(_alive, workers)) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not [w for w in workers if _alive(w)], "pool workers outlived osg collect"
    finally:
        parent.kill()
        for pid in workers:
            if _alive(pid):
                os.kill(pid, signal.SIGKILL)


def test_long_jobs_default_to_the_machines_cpus() -> None:
    import os

    from osg_control.cli import build_parser, main
    from osg_control.parallel.machine import machine_cpus

    cpus = machine_cpus()
    assert cpus == len(os.sched_getaffinity(0)) >= 1
    args = build_parser(["reproduce"]).parse_args(["reproduce", "--out", "x"])
    assert (args.workers, args.threads) == (cpus, cpus)
    assert main(["reproduce", "--out", "x", "--threads", "0"]) == 2


HALF_SENT_RESULT = """
import gc, os, signal, struct, sys, time
from multiprocessing.queues import SimpleQueue
from osg_control.parallel import LocalExecutor

def half_sent(_):
    # what a worker killed while sending a large result leaves: a message header
    # announcing 1 GiB, a few bytes of it, and no more
    results = next(o for o in gc.get_objects() if isinstance(o, SimpleQueue))
    os.write(results._writer.fileno(), struct.pack("!i", 1 << 30) + b"partial")
    time.sleep(120)

def interrupt(*_):
    raise KeyboardInterrupt

if __name__ == "__main__":
    signal.signal(signal.SIGALRM, interrupt)
    signal.alarm(3)  # Ctrl-C while the pool's manager thread waits for the rest
    try:
        list(LocalExecutor(2).map(half_sent, range(4)))
    except KeyboardInterrupt:
        print("interrupted", flush=True)
    sys.exit(0)
"""


@pytest.mark.slow
def test_an_interrupt_while_a_result_is_half_sent_still_exits(tmp_path: Path) -> None:
    """The pool's manager thread, blocked reading a result its killed worker never
    finished, must not hang the process's exit (the flake of the billion-episode test)."""
    script = tmp_path / "half_sent.py"
    script.write_text(HALF_SENT_RESULT)
    started = time.monotonic()
    done = subprocess.run(
        [sys.executable, str(script)], check=False, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0 and done.stdout.strip() == "interrupted", done.stderr
    assert time.monotonic() - started < 30


def test_an_interrupt_a_finalizer_swallowed_still_ends_the_job() -> None:
    """Ctrl-C's KeyboardInterrupt is lost if it lands in a finalizer; the mark its handler
    sets ends the job at the next result, and the jobs in flight are cancelled."""
    cancelled: list[int] = []
    mapped = windowed(lambda x: x, lambda x: 3 * x, cancelled.append, iter(range(10)), 3)
    assert next(mapped) == 0
    INTERRUPTED.set()
    try:
        with pytest.raises(KeyboardInterrupt):
            next(mapped)
    finally:
        INTERRUPTED.clear()
    assert cancelled == [2, 3]


def test_handle_errors_marks_ctrl_c_and_restores_the_handlers() -> None:
    """Within ``handle_errors`` Ctrl-C raises KeyboardInterrupt and sets the mark (exit 130);
    the mark starts clear and is cleared after (a later job in this process runs on), and
    the process's own handlers come back."""
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    marked = []
    INTERRUPTED.set()  # left over from elsewhere in this process
    with handle_errors() as outcome:
        assert not INTERRUPTED.is_set()
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)  # the handler raises at the next bytecode
        except KeyboardInterrupt:
            marked.append(INTERRUPTED.is_set())
            raise
    assert marked == [True] and outcome.code == EXIT_CODES["interrupted"]
    assert not INTERRUPTED.is_set()
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before
