"""Every ```python block in README.md and docs/*.md runs, one test per block (its id names the
file and line), so an example cannot rot.

A block runs alone in a fresh namespace, from the repository root, with ``OSG_CACHE_DIR`` set
to a temporary folder (so nothing it writes lands in the user's cache). An HTML comment on the
line just above the opening fence changes that:

- ``<!-- doc-test: in MODULE -->`` runs the block in a copy of MODULE's namespace: for an
  excerpt of a file (docs/domains.md quotes ``tests/minidomain``), so every name it uses must
  exist there and its code must run there;
- ``<!-- doc-test: skip REASON -->`` skips it with REASON; kept rare (``MAX_SKIPS``) and
  counted by ``test_skipped_examples_are_few_and_say_why``.
"""

from __future__ import annotations

import importlib
import re
from dataclasses import dataclass
from pathlib import Path

import pytest

from osg_control.domain import registry

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
MARKER = re.compile(r"<!--\s*doc-test:\s*(skip|in)\s+(.*?)\s*-->")
MAX_SKIPS = 2
"""At most this many examples may be skipped (each with its reason in the Markdown)."""


@dataclass(frozen=True)
class Example:
    """One ```python block: where it is, its code, and its marker (if any)."""

    page: Path
    line: int
    code: str
    marker: tuple[str, str] | None

    @property
    def id(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def examples(page: Path) -> list[Example]:
    """The ```python blocks of a Markdown page, in order; ``line`` is the opening fence's."""
    lines = page.read_text(encoding="utf-8").splitlines()
    found: list[Example] = []
    i = 0
    while i < len(lines):
        if lines[i].strip() == "```python":
            start = i
            end = next((j for j in range(i + 1, len(lines)) if lines[j].strip() == "```"), None)
            if end is None:
                raise ValueError(f"{page}:{start + 1}: a ```python block is never closed")
            above = lines[start - 1] if start > 0 else ""
            match = MARKER.search(above)
            marker = (match.group(1), match.group(2)) if match else None
            code = "\n".join(lines[start + 1 : end]) + "\n"
            found.append(Example(page, start + 1, code, marker))
            i = end
        i += 1
    return found


ALL = [example for page in PAGES for example in examples(page)]


def test_the_pages_have_examples() -> None:
    assert len(ALL) >= 10, [e.id for e in ALL]


def test_skipped_examples_are_few_and_say_why() -> None:
    skipped = [e for e in ALL if e.marker and e.marker[0] == "skip"]
    assert len(skipped) <= MAX_SKIPS, [e.id for e in skipped]
    for example in skipped:
        assert len(example.marker[1].split()) >= 4, f"{example.id}: say why it is skipped"


def test_a_marker_names_its_kind() -> None:
    for page in PAGES:
        for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
            if "doc-test:" in line:
                assert MARKER.search(line), f"{page.name}:{number}: unknown doc-test marker"


@pytest.mark.parametrize("example", ALL, ids=[e.id for e in ALL])
def test_example_runs(example: Example, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    if example.marker and example.marker[0] == "skip":
        pytest.skip(example.marker[1])
    monkeypatch.chdir(ROOT)
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path / "cache"))
    # An example may register a domain: the registry is restored afterwards.
    monkeypatch.setattr(registry, "_FACTORIES", dict(registry._FACTORIES))
    monkeypatch.setattr(registry, "_BUILT", dict(registry._BUILT))
    namespace: dict[str, object] = {"__name__": "__doc_example__"}
    if example.marker and example.marker[0] == "in":
        namespace = dict(vars(importlib.import_module(example.marker[1])))
    exec(compile(example.code, example.id, "exec"), namespace)


LINK = re.compile(r"\]\(([^)\s]+)\)")


def _anchor(heading: str) -> str:
    """GitHub's anchor of a Markdown heading: lower case, punctuation dropped, spaces to '-'."""
    text = heading.strip().lstrip("#").strip().lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def test_links_between_pages_resolve() -> None:
    """Every relative link in README.md, CONTRIBUTING.md and docs/ names a file that exists and,
    with a #fragment, a heading of that file."""
    broken = []
    for page in [*PAGES, ROOT / "CONTRIBUTING.md"]:
        for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
            for target in LINK.findall(line):
                if re.match(r"[a-z]+:", target):
                    continue
                name, _, fragment = target.partition("#")
                linked = (page.parent / name).resolve() if name else page
                if not linked.exists():
                    broken.append(f"{page.name}:{number}: {target} (no such file)")
                    continue
                if fragment and linked.suffix == ".md":
                    headings = [
                        _anchor(h)
                        for h in linked.read_text(encoding="utf-8").splitlines()
                        if h.startswith("#")
                    ]
                    if fragment not in headings:
                        broken.append(f"{page.name}:{number}: {target} (no such heading)")
    assert not broken, "\n".join(broken)


def test_the_readme_stays_a_quick_read() -> None:
    """Issue 38's shape: at most about 150 lines, the set-up + main-job command and the test
    commands in the first 40, no table cell over 300 characters, at most one commit named
    (the one the shipped defaults come from: measurement history lives in docs/results.md)."""
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 150
    head = "\n".join(lines[:40])
    assert "pip install torch==2.13.0" in head and "osg run --goal" in head
    assert 'pytest -m "not slow"' in head and "pytest -q -x --timeout=900" in head
    cells = [cell for line in lines if line.startswith("|") for cell in line.split("|")]
    assert max(len(cell) for cell in cells) <= 300
    commits = {
        w for w in re.findall(r"\b[0-9a-f]{7,40}\b", "\n".join(lines)) if re.search("[a-f]", w)
    }
    assert len(commits) <= 1, commits
