"""Lazy work: job lists made on demand, and in-order submission with a bounded window.

However many episodes a command asks for, neither its job list nor the jobs in flight
grow with the count: ``Jobs`` makes job ``j`` only when it is asked for, and ``windowed``
keeps at most ``window`` of them submitted, so memory stays flat and the first result
(and its progress line) comes after the first job, not after building them all.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Generic, TypeVar, overload

T = TypeVar("T")
R = TypeVar("R")
C = TypeVar("C")
F = TypeVar("F")
IN_FLIGHT_PER_WORKER = 2
"""Jobs submitted per worker (or Ray CPU) ahead of the one being collected."""
INTERRUPTED = threading.Event()
"""Set by ``osg``'s Ctrl-C and SIGTERM handler (``commands.errors``). The handler's
``KeyboardInterrupt`` is lost when it lands while the main thread runs a finalizer (Python
prints "Exception ignored" and goes on), so ``windowed`` raises it again at the next result."""


class Jobs(Sequence[T], Generic[T]):
    """``count`` jobs, job ``j`` made by ``make(j)`` each time it is asked for."""

    def __init__(self, count: int, make: Callable[[int], T]) -> None:
        self._size = count
        self._make = make

    def __len__(self) -> int:
        return self._size

    @overload
    def __getitem__(self, index: int) -> T: ...

    @overload
    def __getitem__(self, index: slice) -> list[T]: ...

    def __getitem__(self, index: int | slice) -> T | list[T]:
        if isinstance(index, slice):
            return [self._make(j) for j in range(self._size)[index]]
        return self._make(range(self._size)[index])

    def __iter__(self) -> Iterator[T]:
        return map(self._make, range(self._size))


def grid(cells: Sequence[C], per_cell: int, make: Callable[[C, int], T]) -> Jobs[T]:
    """The jobs ``make(cell, i)`` for every cell and ``i < per_cell``, cells outer."""
    return Jobs(len(cells) * per_cell, lambda j: make(cells[j // per_cell], j % per_cell))


def windowed(
    submit: Callable[[T], F],
    result: Callable[[F], R],
    cancel: Callable[[F], object],
    items: Iterable[T],
    window: int,
) -> Iterator[R]:
    """``result(submit(item))`` for every item, in the items' order, with at most ``window``
    submitted and not yet collected; leaving early cancels those."""
    pending: deque[F] = deque()

    def collected() -> R:
        done = result(pending.popleft())
        if INTERRUPTED.is_set():
            raise KeyboardInterrupt
        return done

    try:
        for item in items:
            pending.append(submit(item))
            if len(pending) >= window:
                yield collected()
        while pending:
            yield collected()
    finally:
        for handle in pending:
            cancel(handle)
