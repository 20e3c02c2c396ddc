"""The package's layering: the generic core imports no domain and names none of its things
nor any robot, and no layer imports one above it."""

from __future__ import annotations

import ast
import importlib.util
import re
from pathlib import Path

import pytest

from osg_control.domain.registry import get_domain
from osg_control.robots.registry import robot_names

PACKAGE = Path(__file__).resolve().parents[1] / "osg_control"
DOMAIN_PACKAGES = ("kitchen", "franka", "libero")
"""Sub-packages that are domains (the only places that may name their things)."""
ROBOT_PACKAGE = "robots"
"""The sub-package of robot modules: with the domains, the only place that names a robot;
the core may import its registry and nothing else of it."""
ROBOT_WORDS = ("panda",)
"""Words that name a robot besides the registered robots' names (``robot_names``)."""
LAYERS: dict[str, int] = {
    "errors": 0, "paths": 0, "seeding": 0, "registration": 0, "io_safety": 0, "json_files": 0,
    "__init__": 0,
    "control": 1, "domain": 1, "parallel": 1, "perception": 1, "robots": 1,
    "environment": 2,
    "data": 3,
    "learning": 4, "planning": 4,
    "classifier": 5,
    "execution": 6,
    "evaluation": 7,
    "pipeline": 8,
    "commands": 9, "cli": 9,
}  # fmt: skip
"""Each top-level module or sub-package's layer: a module may import its own layer or lower."""
KITCHEN_WORDS = ("cube", "door", "handle", "valve", "cabinet", "counter", "kitchen")


def _layer(module: str) -> str:
    return module.split(".")[1] if module.count(".") else "__init__"


def _modules() -> list[tuple[str, Path]]:
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        found.append((".".join(parts), path))
    return found


def _imports(tree: ast.AST) -> list[str]:
    names = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.append(node.module)
            names += [f"{node.module}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
    return [n for n in names if n.startswith("osg_control.")]


def _strings(tree: ast.AST) -> list[tuple[int, str]]:
    """Every string constant but documentation (docstrings of modules, classes, functions
    and attributes: a string standing alone as a statement), with its line."""
    docstrings = {
        id(node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)
    }
    return [
        (node.lineno, node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant)
        and isinstance(node.value, str)
        and id(node) not in docstrings
    ]


def _core() -> list[tuple[str, Path]]:
    return [(m, p) for m, p in _modules() if _layer(m) not in (*DOMAIN_PACKAGES, ROBOT_PACKAGE)]


@pytest.mark.parametrize("module,path", _core(), ids=[m for m, _ in _core()])
def test_core_module_imports_no_domain(module: str, path: Path) -> None:
    tree = ast.parse(path.read_text())
    for name in _imports(tree):
        assert _layer(name) not in DOMAIN_PACKAGES, f"{module} imports {name}"


@pytest.mark.parametrize("module,path", _core(), ids=[m for m, _ in _core()])
def test_core_module_imports_no_robot(module: str, path: Path) -> None:
    """The core reaches a robot through the registry only (``robots.registry.get_robot``)."""
    for name in _imports(ast.parse(path.read_text())):
        if _layer(name) == ROBOT_PACKAGE:
            assert name.startswith("osg_control.robots.registry"), f"{module} imports {name}"


def _robot_words_in(text: str) -> list[tuple[int, str]]:
    """(line, word) of every robot word in ``text``: code, strings, comments and docs."""
    words = {*ROBOT_WORDS, *robot_names()}
    patterns = {w: re.compile(rf"(?<![a-z]){re.escape(w)}(?![a-z])") for w in sorted(words)}
    return [
        (number, word)
        for number, line in enumerate(text.lower().splitlines(), 1)
        for word, pattern in patterns.items()
        if pattern.search(line)
    ]


def test_core_names_no_robot() -> None:
    """No core module, command line help included, names a robot: each one is data in
    ``osg_control.robots`` (``control.description.RobotDescription``)."""
    offending = [
        f"{path.relative_to(PACKAGE)}:{line}: {word}"
        for _, path in _core()
        for line, word in _robot_words_in(path.read_text())
    ]
    assert not offending, "\n".join(offending)


def test_the_robot_word_check_finds_the_old_welded_panda() -> None:
    """The check refuses what the core held before robots were descriptions (e88d9eb's
    ``control/robot.py``, ``with_panda`` in ``control/scene_model.py``)."""
    old = 'ARM_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))\ndef with_panda(): ...\n'
    assert _robot_words_in(old) == [(1, "panda"), (2, "panda")]
    assert _robot_words_in("import pandas  # a word that holds a robot's name") == []


def test_no_layer_imports_one_above_it() -> None:
    upward = []
    for module, path in _modules():
        if _layer(module) in DOMAIN_PACKAGES:
            continue
        own = LAYERS[_layer(module)]
        for name in _imports(ast.parse(path.read_text())):
            other = _layer(name)
            if other in LAYERS and LAYERS[other] > own:
                upward.append(f"{module} -> {name}")
    assert not upward, upward


def test_core_strings_name_no_kitchen_thing() -> None:
    kitchen = get_domain("kitchen")
    names = {s.name for s in kitchen.skills} | set(kitchen.facts) | set(kitchen.nodes)
    names |= {t.name for t in kitchen.tasks}
    offending = []
    for module, path in _core():
        if _layer(module) in ("commands", "cli"):
            continue  # CLI help and examples may show the default domain's things as text
        for line, text in _strings(ast.parse(path.read_text())):
            lowered = text.lower()
            words = [w for w in KITCHEN_WORDS if w in lowered]
            if words or lowered in names:
                offending.append(f"{path.relative_to(PACKAGE)}:{line}: {text!r}")
    assert not offending, "\n".join(offending)


def test_every_layer_is_classified() -> None:
    unknown = {_layer(m) for m, _ in _modules()} - set(LAYERS) - set(DOMAIN_PACKAGES)
    assert not unknown, f"add {sorted(unknown)} to LAYERS"


DECIDING_LAYERS = ("execution", "classifier", "learning")
"""Layers that decide (or learn to): they read percepts, never the simulator's state."""
TRUTH_ATTRIBUTES = (
    "facts",
    "skill_success",
    "world_state",
    "read_world",
    "tcp_pose",
    "world",
    "arm_q",
    "data",
    "model",
    "scene",
)
"""The env's truth accessors (``domain.contract``) and the simulator itself."""
TRUTH_KEYS = ("world", "world_facts")
"""The step info's truth entries."""


def _truth_reads(tree: ast.AST) -> list[str]:
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr in TRUTH_ATTRIBUTES:
            owner = node.value
            if isinstance(owner, ast.Name) and owner.id == "env":
                found.append(f"line {node.lineno}: env.{node.attr}")
        if (
            isinstance(node, ast.Subscript)
            and isinstance(node.slice, ast.Constant)
            and node.slice.value in TRUTH_KEYS
        ):
            found.append(f"line {node.lineno}: [{node.slice.value!r}]")
    found += [
        f"imports {name}" for name in _imports(tree) if name.startswith("osg_control.kitchen")
    ]
    found += [
        f"line {node.lineno}: imports mujoco"
        for node in ast.walk(tree)
        if isinstance(node, ast.Import)
        and any(a.name == "mujoco" for a in node.names)
        or isinstance(node, ast.ImportFrom)
        and node.module == "mujoco"
    ]
    return found


@pytest.mark.parametrize(
    "module,path",
    [(m, p) for m, p in _core() if _layer(m) in DECIDING_LAYERS],
    ids=[m for m, _ in _core() if _layer(m) in DECIDING_LAYERS],
)
def test_deciding_layers_read_no_simulator_state(module: str, path: Path) -> None:
    """execution/, classifier/ and learning/ read percepts (``env.percept()``), never the
    env's truth accessors, the step info's truth, or MuJoCo."""
    assert _truth_reads(ast.parse(path.read_text())) == [], module


def test_the_truth_check_finds_a_truth_read() -> None:
    source = "def f(env, info):\n    env.facts()\n    return info['world']\n"
    assert sorted(_truth_reads(ast.parse(source))) == ["line 2: env.facts", "line 3: ['world']"]


ARM_ENV_MODULE = "osg_control.environment.arm_env"
"""Where ``ArmEnv`` lives: the core types against ``domain.contract.SkillEnv`` instead."""


def test_the_core_types_against_the_contract_never_arm_env() -> None:
    """No core module outside ``environment/`` imports ``ArmEnv``: collection, evaluation
    and execution take any env that implements ``SkillEnv`` (FrankaKitchen's adapter, a
    user's own)."""
    offending = [
        f"{module} imports {name}"
        for module, path in _core()
        if _layer(module) != "environment"
        for name in _imports(ast.parse(path.read_text()))
        if name in (f"{ARM_ENV_MODULE}.ArmEnv", "osg_control.environment.ArmEnv")
    ]
    assert not offending, offending


def test_the_arm_env_check_finds_an_import_of_it() -> None:
    """The check above sees an ``ArmEnv`` import where it is (the check can fail)."""
    tree = ast.parse(f"from {ARM_ENV_MODULE} import ArmEnv, EnvConfig\n")
    assert f"{ARM_ENV_MODULE}.ArmEnv" in _imports(tree)


def test_every_package_import_names_a_module_that_exists() -> None:
    """mypy runs with ``ignore_missing_imports`` (for third-party packages), so it would let
    an import of a removed ``osg_control`` module through; this does not (package, tests,
    tools)."""
    root = PACKAGE.parent
    files = [
        *PACKAGE.rglob("*.py"),
        *(root / "tests").rglob("*.py"),
        *(root / "tools").glob("*.py"),
    ]
    missing = []
    for path in files:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                modules = [node.module]
            elif isinstance(node, ast.Import):
                modules = [alias.name for alias in node.names]
            else:
                continue
            for module in modules:
                if module.startswith("osg_control") and importlib.util.find_spec(module) is None:
                    missing.append(f"{path.relative_to(root)}:{node.lineno}: {module}")
    assert not missing, "\n".join(missing)
