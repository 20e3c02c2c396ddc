"""Process facts read from Linux's ``/proc``: a process's parent, state and start time, and
the live descendants of a process (what the Ray watchdog records and kills)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class ProcessStat:
    """The fields of ``/proc/PID/stat`` the package reads."""

    parent: int
    state: str
    """One letter: ``R`` running, ``S`` sleeping, ``Z`` a zombie (exited, not reaped), ..."""
    start: int
    """Start time in clock ticks after boot: with the pid, it names one process (pids are
    reused)."""


def process_stat(pid: int) -> ProcessStat | None:
    """``pid``'s ``ProcessStat``; None if it is gone."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return ProcessStat(parent=int(fields[1]), state=fields[0], start=int(fields[19]))


def live_pids() -> list[int]:
    """Every pid ``/proc`` lists now (zombies included)."""
    return [int(entry.name) for entry in Path("/proc").iterdir() if entry.name.isdigit()]


def descendants(root: int) -> list[tuple[int, int]]:
    """The live descendants of ``root`` (zombies left out) as ``(pid, start time)`` pairs,
    nearest first."""
    children: dict[int, list[tuple[int, int]]] = {}
    for pid in live_pids():
        stat = process_stat(pid)
        if stat is not None and stat.state != "Z":
            children.setdefault(stat.parent, []).append((pid, stat.start))
    found: list[tuple[int, int]] = []
    frontier = [root]
    while frontier:
        for child in children.get(frontier.pop(0), []):
            found.append(child)
            frontier.append(child[0])
    return found
