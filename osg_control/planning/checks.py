"""Meaning checks of PDDL files, before the ``pddl`` package reads them.

Every name is checked against its declaration (predicates, functions, types, constants,
objects, variables, arities, duplicate actions), and every construct the grounding cannot
handle is refused with the requirement it needs. Each error names the file, the line and
the name as spelled there. What passes is within the supported fragment: STRIPS, typing,
negative preconditions and goals, equality, and action costs (constants or static numeric
functions initialised in the problem).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field

from osg_control.errors import PDDLError
from osg_control.planning.sexpr import Atom, List, SExpr

KNOWN_REQUIREMENTS = frozenset(
    ":strips :typing :negative-preconditions :disjunctive-preconditions :equality "
    ":existential-preconditions :universal-preconditions :quantified-preconditions "
    ":conditional-effects :fluents :numeric-fluents :object-fluents :adl :durative-actions "
    ":duration-inequalities :continuous-effects :derived-predicates :timed-initial-literals "
    ":preferences :constraints :action-costs".split()
)
TYPING_IMPLIED_BY = frozenset({":typing", ":adl"})
OBJECT = "object"
TOTAL_COST = "total-cost"
_INTEGER_COST = re.compile(r"[0-9]+(\.0*)?")
"""A cost as a PDDL number with an integer value: digits, and at most a zero fraction."""

_UNSUPPORTED = {
    "or": ":disjunctive-preconditions",
    "imply": ":disjunctive-preconditions",
    "exists": ":existential-preconditions",
    "forall": ":universal-preconditions",
    "when": ":conditional-effects",
    "<": ":numeric-fluents",
    ">": ":numeric-fluents",
    "<=": ":numeric-fluents",
    ">=": ":numeric-fluents",
    "assign": ":numeric-fluents",
    "decrease": ":numeric-fluents",
    "scale-up": ":numeric-fluents",
    "scale-down": ":numeric-fluents",
    ":derived": ":derived-predicates",
    ":durative-action": ":durative-actions",
    ":constraints": ":constraints",
}
"""Constructs beyond the supported fragment and the requirement each needs."""


@dataclass
class Declarations:
    """What a domain declares, in normal form (lower case), for checking its problems."""

    name: str
    types: dict[str, str] = field(default_factory=dict)  # type -> parent
    constants: dict[str, tuple[str, ...]] = field(default_factory=dict)
    predicates: dict[str, int] = field(default_factory=dict)  # name -> arity
    functions: dict[str, int] = field(default_factory=dict)
    requirements: set[str] = field(default_factory=set)
    warnings: list[str] = field(default_factory=list)


class Checker:
    """Checks one file's tree; ``fail`` builds the located error."""

    def __init__(self, path: str) -> None:
        """Remember the file name for messages."""
        self.path = path
        self.spelling: dict[str, str] = {}  # type names as first spelled in the file

    def fail(self, where: SExpr, message: str) -> PDDLError:
        """A ``PDDLError`` for ``path:line: message``."""
        return PDDLError(f"{self.path}:{where.line}: {message}")

    def atom(self, item: SExpr | None, what: str, near: SExpr) -> Atom:
        """``item`` as a name, or an error saying ``what`` was expected."""
        if not isinstance(item, Atom):
            raise self.fail(item or near, f"expected {what}")
        return item

    def unsupported(self, where: SExpr, construct: str) -> PDDLError:
        """The refusal of a construct beyond the supported fragment, naming its requirement."""
        needs = _UNSUPPORTED.get(construct, "a construct")
        return self.fail(
            where,
            f"'{construct}' needs {needs}, which the built-in planner does not support "
            "(supported: :strips :typing :negative-preconditions :equality :action-costs)",
        )

    def typed_list(self, items: Sequence[SExpr], near: SExpr) -> list[tuple[Atom, tuple[str, ...]]]:
        """``a b - t c - (either u v)`` as ``[(a, (t,)), (b, (t,)), (c, (u, v))]``."""
        result: list[tuple[Atom, tuple[str, ...]]] = []
        pending: list[Atom] = []
        i = 0
        while i < len(items):
            item = items[i]
            if isinstance(item, Atom) and item.text == "-":
                kind = items[i + 1] if i + 1 < len(items) else None
                if isinstance(kind, List) and kind.head() == "either":
                    kinds = [self.atom(t, "a type", kind) for t in kind.items[1:]]
                else:
                    kinds = [self.atom(kind, "a type after '-'", item)]
                for atom in kinds:
                    self.spelling.setdefault(atom.text, atom.spelled)
                names = tuple(atom.text for atom in kinds)
                result += [(name, names) for name in pending]
                pending = []
                i += 2
                continue
            pending.append(self.atom(item, "a name", near))
            i += 1
        return result + [(name, ()) for name in pending]

    def check_types(self, kinds: Sequence[str], where: Atom, decl: Declarations) -> None:
        """Every type in ``kinds`` declared (``object`` always is)."""
        for kind in kinds:
            if kind != OBJECT and kind not in decl.types:
                spelled = self.spelling.get(kind, kind)
                raise self.fail(where, f"undeclared type '{spelled}' (of '{where.spelled}')")


def sections(tree: List, checker: Checker, kind: str) -> tuple[Atom, list[List]]:
    """The name of ``(define (kind NAME) sections...)`` and its sections."""
    if tree.head() != "define" or len(tree.items) < 2:
        raise checker.fail(tree, f"expected (define ({kind} NAME) ...)")
    header = tree.items[1]
    if not isinstance(header, List) or header.head() != kind or len(header.items) != 2:
        raise checker.fail(header, f"expected ({kind} NAME) after define")
    body = []
    for item in tree.items[2:]:
        if not isinstance(item, List) or not item.head().startswith(":"):
            raise checker.fail(item, "expected a section such as (:init ...)")
        body.append(item)
    return checker.atom(header.items[1], f"a {kind} name", header), body


class FormulaChecker:
    """Checks preconditions, effects, goals and init facts against the declarations."""

    def __init__(self, checker: Checker, decl: Declarations, objects: dict[str, tuple[str, ...]]):
        """Check with ``decl``'s predicates and functions; ``objects`` are the known names."""
        self.c = checker
        self.decl = decl
        self.objects = objects

    def terms(self, atom: List, scope: set[str], table: dict[str, int], what: str) -> None:
        """``(name term...)``: the name declared in ``table`` with that arity, terms known."""
        name = self.c.atom(atom.items[0] if atom.items else None, f"a {what} name", atom)
        if name.text not in table:
            raise self.c.fail(name, f"undeclared {what} '{name.spelled}'")
        args = atom.items[1:]
        if len(args) != table[name.text]:
            raise self.c.fail(
                name,
                f"{what} '{name.spelled}' takes {table[name.text]} argument(s), got {len(args)}",
            )
        for arg in args:
            term = self.c.atom(arg, "a variable or an object", atom)
            if term.text.startswith("?"):
                if term.text not in scope:
                    raise self.c.fail(term, f"undeclared variable '{term.spelled}'")
            elif term.text not in self.objects:
                raise self.c.fail(term, f"undeclared object '{term.spelled}'")

    def literal(self, item: List, scope: set[str]) -> None:
        """An atom, an equality, or the negation of one of them."""
        head = item.head()
        if head == "not":
            inner = item.items[1] if len(item.items) == 2 else None
            if not isinstance(inner, List) or inner.head() in ("and", "not", *_UNSUPPORTED):
                raise self.c.fail(item, "(not ...) must hold one atom or equality")
            self.literal(inner, scope)
        elif head == "=":
            if len(item.items) != 3 or any(isinstance(t, List) for t in item.items[1:]):
                raise self.c.unsupported(item, ">")  # a numeric comparison
            self.terms(item, scope, {"=": 2}, "equality")
        else:
            self.terms(item, scope, self.decl.predicates, "predicate")

    def condition(self, item: SExpr, scope: set[str]) -> None:
        """A precondition or goal: a conjunction of literals (``()`` is empty)."""
        if not isinstance(item, List):
            raise self.c.fail(item, f"expected a formula, got '{item.spelled}'")
        head = item.head()
        if head in _UNSUPPORTED:
            raise self.c.unsupported(item, head)
        if head == "and":
            for part in item.items[1:]:
                self.condition(part, scope)
        elif item.items:
            self.literal(item, scope)

    def cost(self, item: SExpr, scope: set[str]) -> None:
        """The amount of ``(increase (total-cost) amount)``: a number or a function term."""
        if isinstance(item, Atom):
            try:
                float(item.text)
            except ValueError:
                raise self.c.fail(item, f"expected a cost, got '{item.spelled}'") from None
            if not _INTEGER_COST.fullmatch(item.text):  # no sign, exponent, nan or inf
                raise self.c.fail(item, f"action cost {item.spelled} is not a non-negative integer")
        elif item.head() in self.decl.functions and item.head() != TOTAL_COST:
            self.terms(item, scope, self.decl.functions, "function")
        else:
            head = item.head() or "()"
            if head in ("+", "-", "*", "/"):
                raise self.c.fail(
                    item,
                    f"'{head}' in an action cost needs :numeric-fluents, which the "
                    "built-in planner does not support",
                )
            self.terms(item, scope, self.decl.functions, "function")

    def effect(self, item: SExpr, scope: set[str]) -> None:
        """An effect: a conjunction of atoms, negated atoms and one total-cost increase."""
        if not isinstance(item, List):
            raise self.c.fail(item, f"expected an effect, got '{item.spelled}'")
        head = item.head()
        if head == "forall":
            raise self.c.unsupported(item, "when")
        if head in _UNSUPPORTED:
            raise self.c.unsupported(item, head)
        if head == "and":
            for part in item.items[1:]:
                self.effect(part, scope)
        elif head == "increase":
            target = item.items[1] if len(item.items) == 3 else None
            if not isinstance(target, List) or target.head() != TOTAL_COST:
                raise self.c.unsupported(item, "assign")
            if TOTAL_COST not in self.decl.functions:
                raise self.c.fail(item, "undeclared function 'total-cost'")
            self.cost(item.items[2], scope)
        elif head == "not":
            inner = item.items[1] if len(item.items) == 2 else None
            if not isinstance(inner, List):
                raise self.c.fail(item, "(not ...) must hold one atom")
            self.terms(inner, scope, self.decl.predicates, "predicate")
        elif item.items:
            self.terms(item, scope, self.decl.predicates, "predicate")

    def init(self, item: SExpr) -> None:
        """An init entry: a ground atom or ``(= (function objects) number)``."""
        if not isinstance(item, List) or not item.items:
            raise self.c.fail(item, "expected a ground atom in :init")
        if item.head() == "=":
            head = item.items[1] if len(item.items) == 3 else None
            if not isinstance(head, List):
                raise self.c.fail(item, "expected (= (function objects) number) in :init")
            self.terms(head, set(), self.decl.functions, "function")
            self.cost(item.items[2], set())
        elif item.head() in _UNSUPPORTED or item.head() in ("and", "not"):
            raise self.c.fail(item, f"'{item.head()}' is not allowed in :init")
        else:
            self.terms(item, set(), self.decl.predicates, "predicate")
