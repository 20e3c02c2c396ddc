"""Reading JSON from users: the one reader every user-facing file, option or stored text
goes through, so every failure is the caller's error type naming the source and what it
should have held, never an internal error or a hang.

Named failures: a missing or unreadable file; more than ``MAX_JSON_BYTES`` (``/dev/zero``
is read up to the bound, not until memory runs out); bytes that are not UTF-8; malformed
JSON; nesting deeper than Python's parser can follow (its ``RecursionError``);
an integer of more than Python's 4,300 digits; ``NaN`` or ``Infinity``, which are not JSON.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from osg_control.errors import OSGError

MAX_JSON_BYTES = 64 * 1024 * 1024
"""The largest JSON file read: every file the project reads is far smaller (the shipped
figures are 40 kB, a checkpoint sidecar a few kB)."""


class JSONFormatError(ValueError):
    """A text that is not the JSON this module reads (see the module)."""


def _refuse_constant(name: str) -> Any:
    raise JSONFormatError(f"{name} is not a JSON number")


def parse_json(text: str | bytes, constants: bool = False) -> Any:
    """The JSON value in ``text`` (bytes must be UTF-8); ``constants``: accept ``NaN``,
    ``Infinity`` and ``-Infinity`` (as other libraries write them, e.g. a Box space's
    unbounded limits in a Minari data set).

    Raises:
        JSONFormatError: any failure the module names, with the reason.
    """
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as err:
            raise JSONFormatError(f"not UTF-8 text ({err})") from None
    try:
        return json.loads(text, parse_constant=None if constants else _refuse_constant)
    except JSONFormatError:
        raise
    except RecursionError:
        raise JSONFormatError("nested too deeply to read") from None
    except json.JSONDecodeError as err:
        raise JSONFormatError(f"not JSON ({err})") from None
    except ValueError as err:  # an integer over Python's digit limit
        raise JSONFormatError(f"a number too large to read ({err})") from None


def load_json(path: Path, limit: int | None = None) -> Any:
    """The JSON value in the file ``path``, read no further than ``limit`` bytes (default
    ``MAX_JSON_BYTES``).

    Raises:
        OSError: the file cannot be opened or read.
        JSONFormatError: larger than ``limit``, or not JSON (see the module).
    """
    limit = MAX_JSON_BYTES if limit is None else limit
    with open(path, "rb") as stream:
        data = stream.read(limit + 1)
    if len(data) > limit:
        raise JSONFormatError(f"larger than {limit} bytes")
    return parse_json(data)


def read_json(path: Path, what: str, error: type[OSGError], limit: int | None = None) -> Any:
    """The JSON value in the file ``path`` (a ``what``, e.g. "checkpoint sidecar"), read
    no further than ``limit`` bytes (default ``MAX_JSON_BYTES``).

    Raises:
        error: the file is missing, unreadable, larger than ``limit`` or not JSON (see the
            module); the message names the file and ``what``.
    """
    try:
        return load_json(path, limit)
    except FileNotFoundError:
        raise error(f"{path}: {what} not found") from None
    except OSError as err:
        raise error(f"{path}: unreadable {what} ({err})") from err
    except JSONFormatError as err:
        raise error(f"{path}: corrupt {what} ({err})") from None


def read_json_object(path: Path, what: str, error: type[OSGError]) -> dict[str, Any]:
    """The JSON object in ``path`` (a ``what``, e.g. "checkpoint sidecar").

    Raises:
        error: as ``read_json``, or the value is not an object; names the file and ``what``.
    """
    data = read_json(path, what, error)
    if not isinstance(data, dict):
        raise error(f"{path}: corrupt {what} (not a JSON object)")
    return data


def dump_json(value: Any, indent: int | None = 2) -> str:
    """``value`` as JSON text for a command's ``--json``: always valid JSON.

    Raises:
        OSGError: the value holds NaN or an infinity (which ``json.dumps`` would print as
            bare ``NaN``, not JSON), naming where.
    """
    try:
        return json.dumps(value, indent=indent, allow_nan=False)
    except ValueError:
        raise OSGError(
            f"the result holds a non-finite number at {_non_finite(value) or '?'}: it has no "
            "JSON form (a bug: please report it)"
        ) from None


def _non_finite(value: Any, where: str = "") -> str | None:
    """The path of the first NaN or infinity in ``value``, if any."""
    if isinstance(value, float) and not math.isfinite(value):
        return where or "the top level"
    items = (
        value.items()
        if isinstance(value, dict)
        else enumerate(value)
        if isinstance(value, list | tuple)
        else ()
    )
    for key, item in items:
        found = _non_finite(item, f"{where}[{key!r}]")
        if found:
            return found
    return None


def is_json_number(value: object) -> bool:
    """Whether a value read from JSON is a number (an int or a float; ``true`` and
    ``false`` read as bools, which Python counts as ints, are not)."""
    return isinstance(value, int | float) and not isinstance(value, bool)
