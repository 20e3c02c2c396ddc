"""Reading a JSON object from a user's file: every failure is the caller's error type,
naming the file and what it should have held."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from osg_control.errors import OSGError


def read_json_object(path: Path, what: str, error: type[OSGError]) -> dict[str, Any]:
    """The JSON object in ``path`` (a ``what``, e.g. "checkpoint sidecar").

    Raises:
        error: the file is missing, unreadable, not UTF-8 JSON or not an object; the
            message names the file and ``what``.
    """
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise error(f"{path}: {what} not found") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise error(f"{path}: corrupt {what} ({err})") from err
    if not isinstance(data, dict):
        raise error(f"{path}: corrupt {what} (not a JSON object)")
    return data


def is_json_number(value: object) -> bool:
    """Whether a value read from JSON is a number (an int or a float; ``true`` and
    ``false`` read as bools, which Python counts as ints, are not)."""
    return isinstance(value, int | float) and not isinstance(value, bool)
