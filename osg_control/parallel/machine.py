"""The CPUs this process may run on: the default worker and thread count of long jobs."""

from __future__ import annotations

import os


def machine_cpus() -> int:
    """CPUs available to this process (its affinity mask where the OS has one), at least 1."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)
