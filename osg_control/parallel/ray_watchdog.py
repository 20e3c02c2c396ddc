"""Ends a local Ray instance when the ``osg`` that started it ends, however it ends.

Ray's GCS, raylet and workers die with their driver, but its dashboard and runtime-env
agents, once the raylet is gone, hang reporting to the dead GCS and outlive a SIGKILLed
``osg``. So ``RayExecutor`` marks the instance it starts (every Ray process inherits
``OWNER_VARIABLE`` from the driver's environment) and runs this watchdog beside it: the
watchdog reads its standard input, a pipe from ``osg``, until the pipe closes (``osg``
closed it, exited or was killed), then kills every process carrying the mark (Linux:
read from ``/proc``). Ray's agents overwrite their environment with their process title
(``setproctitle``), so their mark can vanish: while ``osg`` runs the watchdog also records
the descendants of ``osg`` that are Ray's (``is_ray_process``) once a second (pid and start
time, so a reused pid is spared) and kills those too.

Run as ``python -m osg_control.parallel.ray_watchdog MARK``.
"""

from __future__ import annotations

import os
import select
import signal
import sys
import time
from pathlib import Path

from osg_control.parallel.processes import descendants, live_pids, process_stat

OWNER_VARIABLE = "OSG_RAY_OWNER"
"""The environment variable that marks the processes of a Ray instance ``osg`` started."""
PASSES = 40
"""Scans of ``/proc`` at most, ``PAUSE_S`` apart: a process may be starting (a raylet's
worker or agent being spawned) while the others are killed, so the scans go on until
``EMPTY_PASSES`` in a row find none."""
EMPTY_PASSES = 4
PAUSE_S = 0.25


SURVEY_S = 1.0
"""How often the watchdog records the descendants of ``osg`` while it runs."""


def is_ray_process(pid: int) -> bool:
    """Whether ``pid`` runs Ray: a ``ray::`` title, or a program or script under a ``ray``
    package folder (the GCS, the raylet, the dashboard and its agents)."""
    try:
        argv = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except OSError:
        return False
    return argv[0].startswith(b"ray::") or any(b"/ray/" in word for word in argv)


def ray_descendants(root: int) -> set[tuple[int, int]]:
    """The live descendants of ``root`` that run Ray, as ``(pid, start time)`` pairs."""
    return {(pid, start) for pid, start in descendants(root) if is_ray_process(pid)}


def marked_processes(mark: str, spared: int, known: set[tuple[int, int]]) -> list[int]:
    """Live processes (other than this one and ``spared``) whose environment carries
    ``mark`` or that are in ``known`` (pid and start time)."""
    wanted = f"{OWNER_VARIABLE}={mark}".encode()
    found = []
    for pid in live_pids():
        if pid in (os.getpid(), spared):
            continue
        stat = process_stat(pid)
        if stat is None or stat.state == "Z":
            continue
        try:
            marked = wanted in Path(f"/proc/{pid}/environ").read_bytes()
        except OSError:  # gone, or not ours to read
            marked = False
        if marked or (pid, stat.start) in known:
            found.append(pid)
    return found


def kill_marked(mark: str, spared: int, known: set[tuple[int, int]] | None = None) -> None:
    """SIGKILL every process but ``spared`` carrying ``mark`` (or in ``known``), until
    ``EMPTY_PASSES`` scans in a row find none (``PASSES`` at most)."""
    empty = 0
    for _ in range(PASSES):
        pids = marked_processes(mark, spared, known or set())
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        empty = 0 if pids else empty + 1
        if empty == EMPTY_PASSES:
            return
        time.sleep(PAUSE_S)


def main(mark: str) -> None:
    """Wait for standard input to close, recording the descendants of ``osg`` meanwhile,
    then kill the marked and recorded processes (never ``osg``, the parent it started with,
    should it still run)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is for osg; the pipe says when
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    driver = os.getppid()
    known: set[tuple[int, int]] = set()
    stdin = sys.stdin.buffer.fileno()
    while True:
        ready, _, _ = select.select([stdin], [], [], SURVEY_S)
        if ready and not os.read(stdin, 4096):
            break
        known |= ray_descendants(driver)
    kill_marked(mark, driver, known)


if __name__ == "__main__":  # pragma: no cover
    main(sys.argv[1])
