"""Read any domain/problem pair a user hands the planner, as Fast Downward would.

PDDL names are case-insensitive, so the text is put in one normal form (ASCII lower case,
every character keeping its line and column) before the ``pddl`` package reads it; messages
quote the file's spelling. The meaning checks (``planning.checks``) run first, with file and
line. The ``pddl`` package is then handed the requirements it needs to accept what the
checks let through (Fast Downward does not check requirement lists either): ``:types``
without ``:typing`` is read with a warning, ``object`` declared as a type is dropped, and
static numeric cost functions get ``:numeric-fluents`` for the parser.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pddl.core import Domain, Problem
from pddl.parser.domain import DomainParser
from pddl.parser.problem import ProblemParser

from osg_control.errors import PDDLError
from osg_control.planning.checks import (
    KNOWN_REQUIREMENTS,
    OBJECT,
    TOTAL_COST,
    TYPING_IMPLIED_BY,
    Checker,
    Declarations,
    FormulaChecker,
    sections,
)
from osg_control.planning.pddl_parse import _describe
from osg_control.planning.sexpr import Atom, List, lower_ascii, parse


@dataclass(frozen=True)
class ParsedPair:
    """A checked and parsed domain/problem pair, with the warnings met on the way."""

    domain: Domain
    problem: Problem
    warnings: tuple[str, ...]


def _read_text(path: Path, what: str) -> str:
    """The file's text, or a ``PDDLError`` naming it."""
    try:
        return path.read_text()
    except FileNotFoundError:
        raise PDDLError(f"{path}: {what} file not found") from None
    except (OSError, UnicodeDecodeError) as err:
        raise PDDLError(f"{path}: cannot read {what} file ({err})") from err


def _requirements(section: List, checker: Checker) -> set[str]:
    """The declared requirements, each a known PDDL requirement."""
    found = set()
    for item in section.items[1:]:
        req = checker.atom(item, "a requirement such as :strips", section)
        if req.text not in KNOWN_REQUIREMENTS:
            raise checker.fail(req, f"unknown requirement '{req.spelled}'")
        found.add(req.text)
    return found


def _types(section: List, checker: Checker, decl: Declarations) -> list[Atom]:
    """Record ``(:types ...)``; return the ``object`` entries the parser must not see."""
    dropped = []
    for name, parents in checker.typed_list(section.items[1:], section):
        if len(parents) > 1:
            raise checker.fail(name, f"type '{name.spelled}' has an (either ...) supertype")
        if name.text == OBJECT:
            if parents and parents[0] != OBJECT:
                raise checker.fail(name, f"'object' cannot be a subtype of '{parents[0]}'")
            dropped.append(name)
            continue
        decl.types[name.text] = parents[0] if parents else OBJECT
    for name, _ in checker.typed_list(section.items[1:], section):
        checker.check_types([decl.types.get(name.text, OBJECT)], name, decl)
    return dropped


def _skeletons(section: List, checker: Checker, decl: Declarations, table: dict[str, int]) -> None:
    """Record ``(:predicates (p ?x - t) ...)`` or ``(:functions (f ?x) - number ...)``."""
    for item in section.items[1:]:
        if isinstance(item, Atom):
            if item.text in ("-", "number"):
                continue  # the (function) - number annotations
            raise checker.fail(item, f"expected (name ?variable ...), got '{item.spelled}'")
        name = checker.atom(item.items[0] if item.items else None, "a name", item)
        if name.text in table:
            raise checker.fail(name, f"'{name.spelled}' is declared twice")
        params = checker.typed_list(item.items[1:], item)
        for var, kinds in params:
            checker.check_types(kinds, var, decl)
        table[name.text] = len(params)


def _action(item: List, checker: Checker, decl: Declarations, seen: set[str]) -> None:
    """Check one ``(:action name :parameters (...) :precondition F :effect E)``."""
    name = checker.atom(item.items[1] if len(item.items) > 1 else None, "an action name", item)
    if name.text in seen:
        raise checker.fail(name, f"action '{name.spelled}' is defined twice")
    seen.add(name.text)
    parts = item.items[2:]
    keys = [p.text for p in parts[::2] if isinstance(p, Atom)]
    if len(parts) % 2 or keys != [
        p for p in keys if p in (":parameters", ":precondition", ":effect")
    ]:
        raise checker.fail(
            item, f"action '{name.spelled}': expected :parameters, :precondition, :effect"
        )
    body = dict(zip(keys, parts[1::2], strict=False))
    scope = set()
    params = body.get(":parameters")
    if isinstance(params, List):
        for var, kinds in checker.typed_list(params.items, params):
            if not var.text.startswith("?"):
                raise checker.fail(var, f"parameter '{var.spelled}' must start with '?'")
            checker.check_types(kinds, var, decl)
            scope.add(var.text)
    formulas = FormulaChecker(checker, decl, decl.constants)
    if ":precondition" in body:
        formulas.condition(body[":precondition"], scope)
    if ":effect" in body:
        formulas.effect(body[":effect"], scope)


def check_domain(tree: List, path: str) -> tuple[Declarations, list[Atom]]:
    """Check a domain's tree; return its declarations and the atoms to drop for the parser."""
    checker = Checker(path)
    name, body = sections(tree, checker, "domain")
    decl = Declarations(name.text)
    dropped: list[Atom] = []
    actions: set[str] = set()
    types_section: List | None = None
    for section in body:
        head = section.head()
        if head == ":requirements":
            decl.requirements |= _requirements(section, checker)
        elif head == ":types":
            types_section = section
            dropped += _types(section, checker, decl)
        elif head == ":constants":
            for const, kinds in checker.typed_list(section.items[1:], section):
                checker.check_types(kinds, const, decl)
                decl.constants[const.text] = kinds
        elif head == ":predicates":
            _skeletons(section, checker, decl, decl.predicates)
        elif head == ":functions":
            _skeletons(section, checker, decl, decl.functions)
        elif head == ":action":
            _action(section, checker, decl, actions)
        elif head in (":derived", ":durative-action", ":constraints"):
            raise checker.unsupported(section, head)
        else:
            raise checker.fail(section, f"unknown domain section '{section.head()}'")
    if types_section is not None and not decl.requirements & TYPING_IMPLIED_BY:
        decl.warnings.append(
            f"{path}:{types_section.line}: :types without :typing among the requirements; "
            "read as typed (as Fast Downward does)"
        )
    return decl, dropped


def check_problem(tree: List, path: str, decl: Declarations) -> None:
    """Check a problem's tree against its domain's declarations."""
    checker = Checker(path)
    _, body = sections(tree, checker, "problem")
    objects = dict(decl.constants)
    for section in body:
        head = section.head()
        if head == ":domain":
            domain = checker.atom(
                section.items[1] if len(section.items) > 1 else None, "a name", section
            )
            if domain.text != decl.name:
                raise checker.fail(
                    domain, f"problem is for domain '{domain.spelled}', not '{decl.name}'"
                )
        elif head == ":requirements":
            _requirements(section, checker)
        elif head == ":objects":
            for obj, kinds in checker.typed_list(section.items[1:], section):
                checker.check_types(kinds, obj, decl)
                objects[obj.text] = kinds
    formulas = FormulaChecker(checker, decl, objects)
    for section in body:
        head = section.head()
        if head == ":init":
            for item in section.items[1:]:
                formulas.init(item)
        elif head == ":goal":
            for item in section.items[1:]:
                formulas.condition(item, set())
        elif head == ":metric":
            words = [a.text if isinstance(a, Atom) else a.head() for a in section.items[1:]]
            if words != ["minimize", TOTAL_COST] or TOTAL_COST not in decl.functions:
                raise checker.fail(section, "only (:metric minimize (total-cost)) is supported")
        elif head not in (":domain", ":requirements", ":objects"):
            raise checker.fail(
                section, f"unknown or unsupported problem section '{section.head()}'"
            )


def _parser_text(text: str, tree: List, decl: Declarations, dropped: list[Atom]) -> str:
    """The normal-form text, with the requirements the ``pddl`` parser needs, no ``object`` type."""
    needed = {":strips", ":typing", ":negative-preconditions", ":equality"}
    if TOTAL_COST in decl.functions:
        needed.add(":action-costs")
    if set(decl.functions) - {TOTAL_COST}:
        needed.add(":numeric-fluents")
    listing = f"(:requirements {' '.join(sorted(needed))})"
    edits: list[tuple[int, int, str]] = [(a.start, a.end, " " * (a.end - a.start)) for a in dropped]
    old = [s for s in tree.items[2:] if isinstance(s, List) and s.head() == ":requirements"]
    if old:
        edits += [(s.start, s.end, "") for s in old[1:]]
        edits.append((old[0].start, old[0].end, listing))
    elif isinstance(tree.items[1], List) and tree.items[1].head() == "domain":
        edits.append((tree.items[1].end, tree.items[1].end, " " + listing))
    lowered = lower_ascii(text)
    for start, end, new in sorted(edits, reverse=True):
        lowered = lowered[:start] + new + lowered[end:]
    return lowered


def read_pair(domain_file: str | Path, problem_file: str | Path) -> ParsedPair:
    """Check and parse a domain/problem pair.

    Raises:
        PDDLError: a file is missing, malformed, refers to an undeclared name, or uses a
            construct the planner does not support (file, line and name given).
    """
    paths = (Path(domain_file), Path(problem_file))
    texts = (_read_text(paths[0], "domain"), _read_text(paths[1], "problem"))
    trees = (parse(texts[0], str(paths[0])), parse(texts[1], str(paths[1])))
    decl, dropped = check_domain(trees[0], str(paths[0]))
    check_problem(trees[1], str(paths[1]), decl)
    parsed: list[Domain | Problem] = []
    for path, text, tree, parser, drop in zip(
        paths, texts, trees, (DomainParser(), ProblemParser()), (dropped, []), strict=True
    ):
        try:
            parsed.append(parser(_parser_text(text, tree, decl, drop)))
        except Exception as err:  # lark, pddl and builtin errors alike: all mean a bad file
            raise PDDLError(_describe(path, text, err)) from err
    domain, problem = parsed
    assert isinstance(domain, Domain) and isinstance(problem, Problem)
    return ParsedPair(domain, problem, tuple(decl.warnings))
