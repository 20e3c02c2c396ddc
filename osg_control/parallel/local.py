"""The local backend: this process, or a process pool whose workers die with their parent.

Pool workers ignore SIGINT: Ctrl-C reaches the whole process group, and only ``osg`` (the
parent) handles it, terminating the pool, so no worker prints a traceback.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Generator, Iterable
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any, TypeVar

from osg_control.parallel.lazy import IN_FLIGHT_PER_WORKER, windowed

T = TypeVar("T")
R = TypeVar("R")
PR_SET_PDEATHSIG = 1
"""``prctl`` option (linux/prctl.h): the signal a process gets when its parent exits."""


def _watch_parent(parent: int) -> None:
    """Exit this process as soon as ``parent`` is no longer its parent (it died)."""
    while os.getppid() == parent:
        time.sleep(0.5)
    os._exit(1)


def die_with_parent(parent: int) -> None:
    """Pool initializer: end this worker when ``parent`` dies, even by SIGKILL.

    Linux: the kernel sends SIGKILL on the parent's death (``PR_SET_PDEATHSIG``); elsewhere
    a daemon thread polls the parent id. Either way no orphan outlives ``osg``.
    """
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) == 0:
            if os.getppid() != parent:  # the parent died before prctl took effect
                os._exit(1)
            return
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()


def _init_worker(parent: int) -> None:
    """Pool initializer: leave Ctrl-C to the parent, die with it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent(parent)


def _terminate(pool: ProcessPoolExecutor) -> None:
    """Drop the pool's queued jobs and SIGKILL its workers now (running jobs are abandoned;
    a signal handler inherited from the parent, e.g. Ray's, must not run in them).

    A worker killed while sending a large result (a chunk of episodes) leaves half a
    message in the result pipe; the pool's manager thread, blocked reading the rest, would
    then hang this process's exit, which joins that thread. This process holds the pipe's
    last writing end, so it closes it: the reader gets end-of-file once the workers are
    gone and the manager thread ends.
    """
    # CPython < 3.14 has no public handle on the workers (3.14: terminate_workers).
    processes: dict[int, Any] = dict(getattr(pool, "_processes", None) or {})
    results = getattr(pool, "_result_queue", None)
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes.values():
        process.kill()
    writer = getattr(results, "_writer", None)
    if writer is not None:
        writer.close()


class LocalExecutor:
    """Runs tasks in this process (``workers=1``) or a local process pool."""

    def __init__(self, workers: int = 1) -> None:
        if workers < 1:
            raise ValueError(f"workers must be >= 1, got {workers}")
        self.workers = workers

    def map(self, fn: Callable[[T], R], items: Iterable[T]) -> Generator[R, None, None]:
        """Apply ``fn`` to every item; results come back in the items' order.

        Items are drawn lazily, ``IN_FLIGHT_PER_WORKER`` per worker ahead; leaving early
        (an error, Ctrl-C, closing the generator) terminates the pool.
        """
        if self.workers == 1:
            yield from map(fn, items)
            return
        pool = ProcessPoolExecutor(
            max_workers=self.workers, initializer=_init_worker, initargs=(os.getpid(),)
        )
        finished = False
        try:
            window = IN_FLIGHT_PER_WORKER * self.workers

            def submit(item: T) -> Future[R]:
                return pool.submit(fn, item)

            yield from windowed(submit, Future.result, Future.cancel, items, window)
            finished = True
        finally:
            if finished:
                pool.shutdown()
            else:
                _terminate(pool)
