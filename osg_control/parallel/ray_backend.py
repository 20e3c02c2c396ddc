"""The Ray backend: one Ray task per item on a cluster, or on a Ray instance started here.

Items and results travel through Ray's object store; each task is retried on another
worker if its worker dies (``MAX_RETRIES``), and results are collected in the items' order,
so a lost worker neither loses nor doubles an item.
"""

from __future__ import annotations

import socket
from collections.abc import Callable, Iterable, Iterator
from typing import Any, TypeVar

from osg_control.errors import BackendError

T = TypeVar("T")
R = TypeVar("R")
MAX_RETRIES = 3
"""Times Ray reruns a task whose worker process died (system failures, not exceptions)."""
CONNECT_TIMEOUT_S = 5.0
"""How long to wait for a cluster's address to accept a connection before giving up."""
RAY_CLIENT_PORT = 10001


def import_ray() -> Any:
    """The ``ray`` module, or a ``BackendError`` saying how to install it."""
    try:
        import ray
    except ImportError as err:
        raise BackendError(
            "the ray backend needs Ray: pip install 'osg-control[ray]' (or pip install ray)"
        ) from err
    return ray


def check_reachable(address: str, timeout: float = CONNECT_TIMEOUT_S) -> None:
    """Fail fast if nothing listens at a ``host:port`` or ``ray://host[:port]`` address.

    ``auto`` (the cluster this machine belongs to) is left to Ray.

    Raises:
        BackendError: naming the address, malformed or unreachable within ``timeout``.
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
        with socket.create_connection((host, int(port_text)), timeout=timeout):
            pass
    except OSError as err:
        raise BackendError(
            f"Ray cluster at {address!r} is unreachable ({err}); start one with "
            f"'ray start --head' and pass the address it prints"
        ) from err


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
        if not self._owned:
            return
        try:
            ray.init(
                address=address,
                num_cpus=num_cpus,
                include_dashboard=False,
                log_to_driver=False,
                configure_logging=False,
            )
        except (ConnectionError, RuntimeError, ValueError) as err:
            where = address or "a new local instance"
            raise BackendError(f"could not start or join Ray at {where}: {err}") from err

    def map(self, fn: Callable[[T], R], items: Iterable[T]) -> Iterator[R]:
        """Submit one task per item; yield the results in the items' order.

        Leaving early (an error or Ctrl-C) cancels the tasks not yet collected.
        """
        remote = self._ray.remote(max_retries=MAX_RETRIES, retry_exceptions=False)(fn)
        refs = [remote.remote(item) for item in items]
        collected = 0
        try:
            for ref in refs:
                yield self._ray.get(ref)
                collected += 1
        finally:
            for ref in refs[collected:]:
                self._ray.cancel(ref)

    def close(self) -> None:
        """Shut Ray down if this executor started or joined it."""
        if self._owned and self._ray.is_initialized():
            self._ray.shutdown()
