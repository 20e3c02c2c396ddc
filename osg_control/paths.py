"""Where artifacts live: the package directory and the user cache directory."""

from __future__ import annotations

import os
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent


def cache_dir() -> Path:
    """Return the artifact directory (``$OSG_CACHE_DIR`` or ``~/.cache/osg-control``)."""
    root = os.environ.get("OSG_CACHE_DIR")
    return Path(root).expanduser() if root else Path.home() / ".cache" / "osg-control"
