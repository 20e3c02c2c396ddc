"""Route MuJoCo's warnings to Python ``logging`` instead of stdout and ``MUJOCO_LOG.TXT``.

MuJoCo's default warning handler prints to stdout and appends to ``MUJOCO_LOG.TXT`` in the
working directory, which then grows with every run. The package installs one handler, once
per process, that logs to the ``osg_control.mujoco`` logger: the empty-prefix notice of the
scene's ``spec.attach`` (harmless: the robot's names are unique) at DEBUG, everything else
(e.g. a divergence) at WARNING. MuJoCo's own warning counters, which the env reads to
detect a divergence, are unaffected.
"""

from __future__ import annotations

import logging

import mujoco

LOGGER = logging.getLogger("osg_control.mujoco")
_EXPECTED = ("Attaching a spec with an empty prefix",)


def _log_warning(message: str) -> None:
    """Log one MuJoCo warning (expected notices at DEBUG)."""
    expected = message.startswith(_EXPECTED)
    LOGGER.log(logging.DEBUG if expected else logging.WARNING, "MuJoCo: %s", message)


def install_warning_handler() -> None:
    """Make ``_log_warning`` MuJoCo's warning handler for this process (idempotent)."""
    mujoco.set_mju_user_warning(_log_warning)
