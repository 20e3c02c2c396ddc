"""Seeds derived from names: stable across processes, platforms and catalogue order."""

from __future__ import annotations

import hashlib

MAX_SEED = 2**32 - 1
"""The largest seed a command or call takes: numpy's legacy and gymnasium's seeding take
32-bit seeds, and the data sets store the seed as a 64-bit HDF5 attribute (a seed of 1e29
ran every episode, then failed writing it)."""


def skill_seed(seed: int, name: str) -> int:
    """Derive a skill's own seed from the run's seed and the skill's name.

    Stable across processes and platforms (unlike ``hash``), so a skill gets the same seed
    whether it is collected or trained alone or with others, and adding a skill to a
    domain changes no other skill's seed.

    Args:
        seed: the run's seed.
        name: the skill's name.

    Returns:
        A seed in [0, 2**63).
    """
    digest = hashlib.sha256(f"{seed}:{name}".encode()).digest()
    return int.from_bytes(digest[:8], "little") >> 1
