"""Find robot description files in the installed example-robot-data package.

example-robot-data is a data-only package: its files lie under
``<site-packages>/cmeel.prefix/share/example-robot-data/`` (or under ``$EXAMPLE_ROBOT_DATA_DIR``,
searched first). Every robot model built from it looks its files up here, by their path inside
that directory, and resolves the ``package://example-robot-data/...`` URIs its URDFs use.
"""

from __future__ import annotations

import os
import site
import sys
from pathlib import Path

from osg_control.errors import ModelNotFoundError

ENV_VARIABLE = "EXAMPLE_ROBOT_DATA_DIR"
"""An example-robot-data directory to search before the installed package."""
PACKAGE_NAME = "example-robot-data"
"""The package's name: its share directory's name and the host of its ``package://`` URIs."""


def data_roots() -> list[Path]:
    """The directories that may hold example-robot-data's files, in search order:
    ``$EXAMPLE_ROBOT_DATA_DIR``, then ``cmeel.prefix/share/example-robot-data`` under every
    site-packages and ``sys.path`` entry, then ``<sys.prefix>/share/example-robot-data``."""
    roots: list[Path] = []
    if os.environ.get(ENV_VARIABLE):
        roots.append(Path(os.environ[ENV_VARIABLE]))
    prefixes = [*site.getsitepackages(), site.getusersitepackages(), *sys.path]
    roots += [Path(prefix) / "cmeel.prefix" / "share" / PACKAGE_NAME for prefix in prefixes]
    roots.append(Path(sys.prefix) / "share" / PACKAGE_NAME)
    return roots


def find_robot_file(relative_path: str) -> Path:
    """The first existing ``root / relative_path`` over ``data_roots()``, e.g.
    ``find_robot_file("robots/ur_description/urdf/ur5_robot.urdf")``.

    Raises:
        ModelNotFoundError: if no root holds the file; lists every path tried.
    """
    tried = []
    for root in data_roots():
        path = root / relative_path
        tried.append(str(path))
        if path.is_file():
            return path
    raise ModelNotFoundError(
        f"{PACKAGE_NAME}'s {relative_path} not found (pip install {PACKAGE_NAME}, or set "
        f"{ENV_VARIABLE}). Searched:\n  " + "\n  ".join(tried)
    )


def resolve_package_uris(text: str, relative_path: str) -> str:
    """``text`` (the file ``relative_path``'s, e.g. a URDF) with its
    ``package://example-robot-data/`` URIs made absolute paths under the root where
    ``find_robot_file(relative_path)`` finds that file.

    Raises:
        ModelNotFoundError: if the file is not found, or a ``package://`` URI of another
            package is left.
    """
    found = find_robot_file(relative_path)
    root = found.parents[len(Path(relative_path).parts) - 1]
    text = text.replace(f"package://{PACKAGE_NAME}/", str(root) + "/")
    if "package://" in text:
        raise ModelNotFoundError(f"unresolved package:// path left in {found}")
    return text
