"""Seeds derived from names: stable across processes, platforms and catalogue order."""

from __future__ import annotations

import hashlib


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
