"""Executor backends: map a function over work items on a local process pool or on Ray.

Work is split by seed, never by arrival order: every item carries its own seed, and each
backend returns the results in the items' order, so the same items give the same results
on any backend and any number of workers or nodes. Both backends draw the items lazily and
keep a bounded number in flight (``parallel.lazy``), so a job list may be as long as asked.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterable, Iterator
from contextlib import contextmanager
from typing import Protocol, TypeVar

from osg_control.errors import BackendError, lookup
from osg_control.parallel.local import LocalExecutor

__all__ = ["BACKENDS", "LocalExecutor", "TaskExecutor", "open_executor"]

T = TypeVar("T")
R = TypeVar("R")


class TaskExecutor(Protocol):
    """Maps a function over items, yielding results in order (local pool, Ray, ...)."""

    def map(self, fn: Callable[[T], R], items: Iterable[T]) -> Generator[R, None, None]:
        """Apply ``fn`` to every item; results come back in the items' order; closing the
        generator early stops the work in flight."""
        ...


BACKENDS: dict[str, str] = {
    "local": "this machine: one process (--workers 1) or a process pool",
    "ray": "a Ray cluster (--address ADDR), or a Ray instance started here",
}
"""The known backends and what each runs on."""


@contextmanager
def open_executor(
    backend: str = "local", workers: int = 1, address: str | None = None
) -> Iterator[TaskExecutor]:
    """An executor of the named backend, closed (Ray shut down if started here) on exit.

    Args:
        backend: one of ``BACKENDS``.
        workers: local processes; for Ray without ``address``, the CPUs of the instance
            started here (a cluster uses all of its CPUs).
        address: a Ray cluster (``host:port``, ``ray://host:port`` or ``auto``); only with
            ``backend="ray"``.

    Raises:
        BackendError: unknown backend (the known ones listed), an address without Ray, Ray
            not installed or its cluster unreachable.
    """
    lookup(BACKENDS, backend, "backend", BackendError)
    if backend == "local":
        if address is not None:
            raise BackendError("--address needs --backend ray (the local backend has none)")
        yield LocalExecutor(workers)
        return
    from osg_control.parallel.ray_backend import RayExecutor

    executor = RayExecutor(address=address, num_cpus=None if address else workers)
    try:
        yield executor
    finally:
        executor.close()
