"""The Ray backend: one Ray task per item on a cluster, or on a Ray instance started here.

Items and results travel through Ray's object store; each task is retried on another
worker if its worker dies (``MAX_RETRIES``), and results are collected in the items' order,
so a lost worker neither loses nor doubles an item. Items are submitted lazily,
``IN_FLIGHT_PER_WORKER`` per cluster CPU ahead of the one being collected.

A Ray instance started here dies with ``osg``, even by SIGKILL: its processes are
marked and a watchdog kills them when ``osg`` ends (``ray_watchdog``, Linux).

Before joining a cluster its address must answer as a gRPC server (HTTP/2) within
``ANSWER_TIMEOUT_S``, so an address that accepts connections but never answers is an error
naming it, not minutes of Ray's own retries.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Generator, Iterable
from functools import partial
from typing import Any, TypeVar

from osg_control.errors import BackendError
from osg_control.parallel.lazy import IN_FLIGHT_PER_WORKER, windowed
from osg_control.parallel.ray_watchdog import OWNER_VARIABLE

T = TypeVar("T")
R = TypeVar("R")
MAX_RETRIES = 3
"""Times Ray reruns a task whose worker process died (system failures, not exceptions)."""
CONNECT_TIMEOUT_S = 5.0
"""How long to wait for a cluster's address to accept a connection before giving up."""
ANSWER_TIMEOUT_S = 10.0
"""How long a connected address may take to answer the HTTP/2 greeting before giving up."""
RAY_CLIENT_PORT = 10001
HTTP2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
"""An HTTP/2 client's connection preface and an empty SETTINGS frame (RFC 9113, 3.4)."""
HTTP2_SETTINGS = 4
"""The frame type a gRPC server answers the preface with (its own SETTINGS)."""


def import_ray() -> Any:
    """The ``ray`` module, or a ``BackendError`` saying how to install it."""
    try:
        import ray
    except ImportError as err:
        raise BackendError(
            "the ray backend needs Ray: pip install 'osg-control[ray]' (or pip install ray)"
        ) from err
    return ray


def check_reachable(
    address: str, timeout: float = CONNECT_TIMEOUT_S, answer_timeout: float = ANSWER_TIMEOUT_S
) -> None:
    """Fail fast unless a gRPC server answers at a ``host:port`` or ``ray://host[:port]``.

    ``auto`` (the cluster this machine belongs to) is left to Ray, and so is the greeting
    with ``RAY_USE_TLS`` set (a TLS server does not answer plain HTTP/2).

    Raises:
        BackendError: naming the address, malformed, unreachable within ``timeout`` or
            silent for ``answer_timeout`` after connecting.
    """
    if address == "auto":
        return
    target = address.removeprefix("ray://")
    host, _, port_text = target.rpartition(":")
    if not host:
        host, port_text = target, str(RAY_CLIENT_PORT) if address.startswith("ray://") else ""
    if not port_text.isdigit():
        raise BackendError(f"Ray address {address!r} is not HOST:PORT, ray://HOST[:PORT] or 'auto'")
    try:
        connection = socket.create_connection((host, int(port_text)), timeout=timeout)
    except OSError as err:
        raise BackendError(
            f"Ray cluster at {address!r} is unreachable ({err}); start one with "
            f"'ray start --head' and pass the address it prints"
        ) from err
    with connection:
        if os.environ.get("RAY_USE_TLS", "0").lower() in ("0", "false", ""):
            _check_answers(connection, address, answer_timeout)


def _check_answers(connection: socket.socket, address: str, timeout: float) -> None:
    """Greet the server as an HTTP/2 client; it must answer with a SETTINGS frame."""
    connection.settimeout(timeout)
    try:
        connection.sendall(HTTP2_PREFACE)
        header = b""
        while len(header) < 9:
            received = connection.recv(9 - len(header))
            if not received:
                raise BackendError(
                    f"Ray cluster at {address!r} closed the connection without answering; "
                    "is it a Ray head node (GCS or Ray client port)?"
                )
            header += received
    except TimeoutError as err:
        raise BackendError(
            f"Ray cluster at {address!r} accepts connections but did not answer within "
            f"{timeout:g} s; is it a Ray head node (GCS or Ray client port)?"
        ) from err
    except OSError as err:
        raise BackendError(f"Ray cluster at {address!r} failed while answering ({err})") from err
    if header[3] != HTTP2_SETTINGS:
        raise BackendError(
            f"Ray cluster at {address!r} answered, but not as a gRPC server; is it a Ray "
            "head node (GCS or Ray client port)?"
        )


def _apply(fn: Callable[[T], R], item: T) -> R:
    """The Ray task: ``fn(item)`` (any callable, e.g. a ``functools.partial``)."""
    return fn(item)


def _task_name(fn: Callable[..., Any]) -> str:
    """The function's name, seen through partials (a worker's title: ``ray::NAME``)."""
    while isinstance(fn, partial):
        fn = fn.func
    return getattr(fn, "__name__", type(fn).__name__)


class RayExecutor:
    """Maps a function over items as Ray tasks (see the module docstring)."""

    def __init__(self, address: str | None = None, num_cpus: int | None = None) -> None:
        """Connect to the cluster at ``address``, or start a local instance of ``num_cpus``.

        A Ray session already open in this process is reused (and left open by ``close``).
        """
        ray = import_ray()
        self._ray = ray
        if address is not None:
            check_reachable(address)
        self._owned = not ray.is_initialized()
        self._remote = ray.remote(max_retries=MAX_RETRIES, retry_exceptions=False)(_apply)
        self._watchdog: subprocess.Popen[bytes] | None = None
        if not self._owned:
            return
        if address is None and sys.platform.startswith("linux"):
            self._watchdog = _start_watchdog()
        in_main_thread = threading.current_thread() is threading.main_thread()
        sigterm = signal.getsignal(signal.SIGTERM)
        try:
            ray.init(
                address=address or "local",  # None would join a cluster RAY_ADDRESS names
                num_cpus=num_cpus,
                include_dashboard=False,
                log_to_driver=False,
                configure_logging=False,
            )
        except (ConnectionError, RuntimeError, ValueError) as err:
            where = address or "a new local instance"
            raise BackendError(f"could not start or join Ray at {where}: {err}") from err
        finally:
            if in_main_thread:  # ray.init makes SIGTERM exit 15; osg's handler makes it 130
                signal.signal(signal.SIGTERM, sigterm)

    def map(self, fn: Callable[[T], R], items: Iterable[T]) -> Generator[R, None, None]:
        """Submit one task per item, lazily; yield the results in the items' order.

        Leaving early (an error or Ctrl-C) cancels the tasks not yet collected.
        """
        ray = self._ray
        remote = self._remote.options(name=_task_name(fn))
        function = ray.put(fn)
        window = IN_FLIGHT_PER_WORKER * max(1, int(ray.cluster_resources().get("CPU", 1)))
        submit = partial(remote.remote, function)
        yield from windowed(submit, ray.get, ray.cancel, items, window)

    def close(self) -> None:
        """Shut Ray down if this executor started or joined it (and end its watchdog)."""
        if self._owned and self._ray.is_initialized():
            self._ray.shutdown()
        if self._watchdog is not None:
            _stop_watchdog(self._watchdog)
            self._watchdog = None


def _start_watchdog() -> subprocess.Popen[bytes]:
    """Mark the Ray processes started from now on and start the watchdog that kills them
    once ``osg`` ends (see ``ray_watchdog``)."""
    mark = f"{os.getpid()}-{time.time_ns()}"
    watchdog = subprocess.Popen(
        [sys.executable, "-m", "osg_control.parallel.ray_watchdog", mark],
        stdin=subprocess.PIPE,
        start_new_session=True,  # a terminal's Ctrl-C is osg's to handle
    )
    os.environ[OWNER_VARIABLE] = mark  # inherited by the GCS, the raylet and all below
    return watchdog


def _stop_watchdog(watchdog: subprocess.Popen[bytes]) -> None:
    """Close the watchdog's pipe (it kills what Ray left) and wait for it."""
    os.environ.pop(OWNER_VARIABLE, None)
    assert watchdog.stdin is not None
    watchdog.stdin.close()
    watchdog.wait(timeout=30)
