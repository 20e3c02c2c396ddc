"""PDDL text as S-expressions whose atoms remember their line and spelling.

The ``pddl`` package's objects carry no positions, so the meaning checks
(``planning.checks``) walk this tree instead and name the line of every name they refuse.
Atoms are in the normal form (lower case, PDDL names being case-insensitive) and keep the
file's spelling for messages.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Union

from osg_control.errors import PDDLError

_TOKEN = re.compile(r";[^\n]*|\(|\)|[^\s();]+")
_UPPER_TO_LOWER = str.maketrans("ABCDEFGHIJKLMNOPQRSTUVWXYZ", "abcdefghijklmnopqrstuvwxyz")


def lower_ascii(text: str) -> str:
    """Lower-case ASCII letters only, so every character keeps its line and column."""
    return text.translate(_UPPER_TO_LOWER)


@dataclass(frozen=True)
class Atom:
    """A name, keyword or number: ``text`` in normal form, ``spelled`` as in the file."""

    text: str
    spelled: str
    line: int
    column: int
    start: int
    end: int


@dataclass(frozen=True)
class List:
    """A parenthesised list and the line of its ``(``."""

    items: tuple[SExpr, ...]
    line: int
    start: int
    end: int

    def head(self) -> str:
        """The first item's text (``""`` when it is missing or a list): the keyword."""
        first = self.items[0] if self.items else None
        return first.text if isinstance(first, Atom) else ""


SExpr = Union[Atom, List]


def parse(text: str, path: str) -> List:
    """Read the one top-level S-expression of a PDDL file.

    Raises:
        PDDLError: unbalanced parentheses or text after the definition (file and line).
    """
    stack: list[tuple[list[SExpr], int, int]] = [([], 1, 0)]
    line_starts = [0, *(m.end() for m in re.finditer("\n", text))]
    line = 1
    for match in _TOKEN.finditer(text):
        token = match.group()
        while line < len(line_starts) and line_starts[line] <= match.start():
            line += 1
        if token.startswith(";"):
            continue
        if token == "(":
            stack.append(([], line, match.start()))
        elif token == ")":
            if len(stack) == 1:
                raise PDDLError(f"{path}:{line}: unexpected ')' (unbalanced parentheses)")
            items, start_line, start = stack.pop()
            stack[-1][0].append(List(tuple(items), start_line, start, match.end()))
        else:
            column = match.start() - line_starts[line - 1] + 1
            stack[-1][0].append(
                Atom(lower_ascii(token), token, line, column, match.start(), match.end())
            )
    if len(stack) > 1:
        raise PDDLError(
            f"{path}:{stack[-1][1]}: '(' never closed: unexpected end of file "
            "(unbalanced parentheses?)"
        )
    top = stack[0][0]
    if len(top) != 1 or not isinstance(top[0], List):
        where = top[1] if len(top) > 1 else (top[0] if top else None)
        line = where.line if where is not None else 1
        raise PDDLError(f"{path}:{line}: expected one (define ...) in the file")
    return top[0]
