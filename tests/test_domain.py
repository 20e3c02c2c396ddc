"""A malformed domain is refused when it is built, naming the domain and the field; an
unknown domain name lists the known ones."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import pytest

from osg_control.cli import main
from osg_control.domain import registry
from osg_control.domain.base import Domain, Task
from osg_control.domain.registry import domain_names, get_domain, register_domain
from osg_control.errors import DomainError

KITCHEN = get_domain("kitchen")
GRAB = KITCHEN.skill("grab-cube")


def _edited(**changes: object) -> Callable[[], Domain]:
    return lambda: dataclasses.replace(KITCHEN, name="broken", **changes)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"skills": ()}, "field 'skills' is empty"),
        ({"facts": ()}, "field 'facts' is empty"),
        ({"skills": (*KITCHEN.skills, GRAB)}, r"duplicate names \['grab-cube'\]"),
        (
            {"skills": (dataclasses.replace(GRAB, end="cube-teleported"),)},
            "skill 'grab-cube' field 'end' names unknown node 'cube-teleported'",
        ),
        (
            {"skills": (dataclasses.replace(GRAB, preconditions=frozenset({"cube-hot"})),)},
            r"skill 'grab-cube' names unknown facts \['cube-hot'\]",
        ),
        (
            {"tasks": (Task("melt", ("cube-melted",)),)},
            r"field 'tasks\[melt\].goal' names unknown facts \['cube-melted'\]",
        ),
        ({"tasks": (Task("nothing", ()),)}, "task 'nothing' has an empty goal"),
        ({"hand_empty": "hands-free"}, r"field 'hand_empty' names unknown facts"),
        ({"home": "attic"}, "field 'home' names unknown node 'attic'"),
        ({"facts_of": None}, "must be callable"),
    ],
)
def test_malformed_domain_is_refused_naming_domain_and_field(
    changes: dict[str, object], message: str
) -> None:
    with pytest.raises(DomainError, match=message) as info:
        _edited(**changes)()
    assert "domain 'broken'" in str(info.value)


def test_unknown_domain_lists_the_known_ones(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(DomainError, match="unknown domain 'attic'; known domains: .*kitchen"):
        get_domain("attic")
    assert main(["--domain", "attic", "plan", "--goal", "door-open"]) == 2
    assert "known domains" in capsys.readouterr().err


def test_registered_factory_must_build_the_named_domain(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(registry, "_FACTORIES", dict(registry._FACTORIES))  # kept to this test
    register_domain("alias", lambda: KITCHEN)
    with pytest.raises(DomainError, match="built a domain named 'kitchen'"):
        get_domain("alias")
    register_domain("not-a-domain", object)  # type: ignore[arg-type]
    with pytest.raises(DomainError, match="returned object"):
        get_domain("not-a-domain")
    assert {"kitchen", "alias", "not-a-domain"} <= set(domain_names())
    assert main(["domains"]) == 1  # the broken ones are named, the good ones still listed


def test_domains_verb_lists_the_kitchen_with_its_valve(capsys: pytest.CaptureFixture[str]) -> None:
    import json

    assert main(["domains", "--json"]) == 0
    listed = {d["name"]: d for d in json.loads(capsys.readouterr().out)}
    kitchen = listed["kitchen"]
    assert {s["name"] for s in kitchen["skills"]} >= {"push-valve-open", "grab-cube"}
    assert "valve-open" in kitchen["facts"] and len(kitchen["start_regions"]) == 8
    assert {t["name"] for t in kitchen["tasks"]} >= {"turn-valve", "open-door-turn-valve"}
