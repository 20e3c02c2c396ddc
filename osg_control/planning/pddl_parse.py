"""Read PDDL files with the ``pddl`` package, naming the file, the line and what the
parser expected when one is malformed."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from pddl.core import Domain, Problem
from pddl.parser.domain import DomainParser
from pddl.parser.problem import ProblemParser

from osg_control.errors import PDDLError

_TERMINALS = {
    "LPAR": "'('",
    "RPAR": "')'",
    "NAME": "a name",
    "QMARK": "'?'",
    **{k.upper(): f"':{k}'" for k in ("action", "derived", "parameters", "precondition")},
    "EFFECT": "':effect'",
}
"""Readable names of the grammar's terminals, for "expected ..." in error messages."""


def _line_of(text: str, message: str) -> int | None:
    """The first line naming a quoted word of ``message`` (for errors lark gives no line)."""
    for word in re.findall(r"'([^'\s]+)'", message):
        pattern = re.compile(rf"(?<![\w-]){re.escape(word)}(?![\w-])")
        for number, line in enumerate(text.splitlines(), start=1):
            if pattern.search(line.split(";", 1)[0]):
                return number
    return None


def _describe(path: Path, text: str, err: Exception) -> str:
    """``path:line:column: what; expected what`` from a lark error, else the line guessed."""
    line = getattr(err, "line", None)
    expected = getattr(err, "expected", None) or getattr(err, "allowed", None) or ()
    names = ", ".join(sorted(_TERMINALS.get(str(e), str(e)) for e in expected))
    token = getattr(err, "token", None)
    if getattr(token, "type", "") == "$END":
        return f"{path}:{line}: unexpected end of file; expected {names} (unbalanced parentheses?)"
    if isinstance(line, int) and line > 0 and names:
        found = repr(str(token)) if token is not None else repr(getattr(err, "char", "?"))
        where = f"{path}:{line}:{getattr(err, 'column', '?')}"
        source = text.splitlines()[line - 1].strip()
        return f"{where}: unexpected {found}; expected {names}\n    {source}"
    message = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    number = _line_of(text, message)
    return f"{path}:{number}: {message}" if number is not None else f"{path}: {message}"


T = TypeVar("T")


def _read(path: str | Path, parse: Callable[[str], T], what: str) -> T:
    """Read and parse a file; callers pass a fresh parser (pddl's keep state between files)."""
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise PDDLError(f"{path}: {what} file not found") from None
    except (OSError, UnicodeDecodeError) as err:
        raise PDDLError(f"{path}: cannot read {what} file ({err})") from err
    try:
        return parse(text)
    except Exception as err:  # lark, pddl and builtin errors alike: all mean a bad file
        raise PDDLError(_describe(path, text, err)) from err


def read_domain(path: str | Path) -> Domain:
    """Parse a PDDL domain file.

    Raises:
        PDDLError: the file is missing or malformed; names the file, the line and what was
            expected there where the parser says.
    """
    return _read(path, DomainParser(), "domain")


def read_problem(path: str | Path) -> Problem:
    """Parse a PDDL problem file.

    Raises:
        PDDLError: the file is missing or malformed; names the file, the line and what was
            expected there where the parser says.
    """
    return _read(path, ProblemParser(), "problem")
