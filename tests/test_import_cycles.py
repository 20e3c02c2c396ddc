"""No import cycle in the package: the modules' import-time imports form a DAG, so no module
is ever seen half-initialised and import order never matters.

Import time is the module's body, class bodies, ``if``/``try`` blocks included; not
function bodies (a factory that imports its implementation when called, e.g. a domain's
``make_env``) and not ``if TYPE_CHECKING:`` blocks (for annotations only).
"""

from __future__ import annotations

import ast
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "osg_control"


def _module_files() -> dict[str, Path]:
    modules = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        modules[".".join(parts)] = path
    return modules


def _is_type_checking(node: ast.AST) -> bool:
    test = node.test if isinstance(node, ast.If) else None
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _import_time_nodes(tree: ast.AST) -> list[ast.AST]:
    """Every node run when the module is imported (module docstring)."""
    found: list[ast.AST] = []
    pending = list(ast.iter_child_nodes(tree))
    while pending:
        node = pending.pop()
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
            continue
        if isinstance(node, ast.If) and _is_type_checking(node):
            pending += node.orelse
            continue
        found.append(node)
        pending += ast.iter_child_nodes(node)
    return found


def import_graph(sources: dict[str, str]) -> dict[str, set[str]]:
    """Module -> the package modules it imports at import time (``from a import b`` is
    module ``a.b`` where that is a module, else ``a``), for ``sources`` (module -> text)."""

    def resolve(name: str) -> str | None:
        while name and name not in sources:
            name = name.rpartition(".")[0]
        return name or None

    graph: dict[str, set[str]] = {}
    for module, text in sources.items():
        names: list[str] = []
        for node in _import_time_nodes(ast.parse(text)):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names += [f"{node.module}.{alias.name}" for alias in node.names]
            elif isinstance(node, ast.Import):
                names += [alias.name for alias in node.names]
        resolved = {resolve(n) for n in names if n.split(".")[0] in _roots(sources)}
        graph[module] = {r for r in resolved if r and r != module}
    return graph


def _roots(sources: dict[str, str]) -> set[str]:
    return {m.split(".")[0] for m in sources}


def import_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` (its modules, the first repeated last), or None."""
    try:
        TopologicalSorter(graph).prepare()
    except CycleError as error:
        return list(error.args[1])
    return None


def test_the_package_has_no_import_cycle() -> None:
    sources = {m: p.read_text() for m, p in _module_files().items()}
    graph = import_graph(sources)
    assert len(graph) == len(list(PACKAGE.rglob("*.py"))) and sum(map(len, graph.values())) > 500
    assert import_cycle(graph) is None, " -> ".join(import_cycle(graph) or [])


def test_the_check_finds_a_cycle_and_ignores_deferred_imports() -> None:
    """A cycle through module bodies (or a class body, or a ``try``) is found; one closed
    only inside a function or under ``TYPE_CHECKING`` is not."""
    cyclic = {
        "pkg.a": "from pkg.b import thing\n",
        "pkg.b": "class B:\n    try:\n        import pkg.c\n    except ImportError:\n        pass",
        "pkg.c": "from pkg import a\n",
        "pkg": "",
    }
    cycle = import_cycle(import_graph(cyclic))
    assert cycle is not None and set(cycle) == {"pkg.a", "pkg.b", "pkg.c"}
    deferred = {
        "pkg.a": "from pkg.b import thing\n",
        "pkg.b": "def make():\n    from pkg.a import x\n",
        "pkg.c": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg.a import x\n",
        "pkg": "import pkg.c\n",
    }
    assert import_cycle(import_graph(deferred)) is None
    assert import_graph(deferred)["pkg.a"] == {"pkg.b"}
