"""Ends a local Ray instance when the ``osg`` that started it ends, however it ends.

Ray's GCS, raylet and workers die with their driver, but its dashboard and runtime-env
agents, once the raylet is gone, hang reporting to the dead GCS and outlive a SIGKILLed
``osg``. So ``RayExecutor`` marks the instance it starts (every Ray process inherits
``OWNER_VARIABLE`` from the driver's environment) and runs this watchdog beside it: the
watchdog reads its standard input, a pipe from ``osg``, until the pipe closes (``osg``
closed it, exited or was killed), then kills every process carrying the mark (Linux:
read from ``/proc``).

Run as ``python -m osg_control.parallel.ray_watchdog MARK``.
"""

from __future__ import annotations

import os
import signal
import sys
import time
from pathlib import Path

OWNER_VARIABLE = "OSG_RAY_OWNER"
"""The environment variable that marks the processes of a Ray instance ``osg`` started."""
PASSES = 40
"""Scans of ``/proc`` at most, ``PAUSE_S`` apart: a process may be starting (a raylet's
worker being spawned) while the others are killed, so the scans go on until two in a row
find none."""
PAUSE_S = 0.25


def marked_processes(mark: str, spared: int) -> list[int]:
    """Live processes (other than this one and ``spared``) whose environment carries
    ``mark``."""
    wanted = f"{OWNER_VARIABLE}={mark}".encode()
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit() or int(entry.name) in (os.getpid(), spared):
            continue
        try:
            marked = wanted in (entry / "environ").read_bytes().split(b"\0")
            state = (entry / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:  # gone, or not ours to read
            continue
        if marked and state != "Z":
            found.append(int(entry.name))
    return found


def kill_marked(mark: str, spared: int) -> None:
    """SIGKILL every process but ``spared`` carrying ``mark``, until two scans in a row find
    none (``PASSES`` at most)."""
    empty = 0
    for _ in range(PASSES):
        pids = marked_processes(mark, spared)
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        empty = 0 if pids else empty + 1
        if empty == 2:
            return
        time.sleep(PAUSE_S)


def main(mark: str) -> None:
    """Wait for standard input to close, then kill the marked processes (never ``osg``,
    the parent it started with, should it still run)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is for osg; the pipe says when
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    driver = os.getppid()
    while sys.stdin.buffer.read(4096):
        pass
    kill_marked(mark, driver)


if __name__ == "__main__":  # pragma: no cover
    main(sys.argv[1])
