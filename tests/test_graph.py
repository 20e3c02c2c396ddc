"""The skill graph: from specs, from synthetic data sets (regions, effects), JSON, PNG, CLI."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from osg_control.cli import main
from osg_control.data.datasets import Dataset, Episode, load_dataset, write_episodes
from osg_control.domain.registry import get_domain
from osg_control.errors import DatasetError, SkillSpecError
from osg_control.kitchen.skills import NODES, SKILLS, SkillSpec
from osg_control.kitchen.world import WorldState, world_facts, world_fields, world_state_from_array
from osg_control.planning.graph import (
    graph_from_specs,
    load_graph,
    save_graph,
)
from osg_control.planning.graph_data import graph_from_datasets
from osg_control.planning.graph_draw import draw_graph

WORLD = ",".join(world_fields())
KITCHEN = get_domain("kitchen")

STEPS = 6


def world_for(facts: frozenset[str]) -> WorldState:
    """A world state whose abstraction is ``facts`` (for the kitchen's consistent fact sets)."""
    if "cube-in-cabinet" in facts:
        cube = (0.64, 0.30, 0.135)
    elif "cube-lifted" in facts:
        cube = (0.50, -0.20, 0.20)
    else:
        cube = (0.50, -0.20, 0.0225)
    return WorldState(
        door_opening=0.4 if "door-open" in facts else 0.0,
        valve_angle=1.0 if "valve-open" in facts else 0.0,
        cube_pos=cube,
        cube_quat=(1.0, 0.0, 0.0, 0.0),
        cube_grasped="holding-cube" in facts,
        handle_grasped="holding-handle" in facts,
    )


def start_facts(spec: SkillSpec) -> frozenset[str]:
    """A consistent world in which the skill's preconditions hold."""
    pre = spec.preconditions
    door = "door-open" if "door-open" in pre or "door-open" in spec.start_facts else "door-closed"
    hand = next((f for f in ("holding-cube", "holding-handle") if f in pre), "hand-empty")
    cube = "cube-lifted" if "cube-lifted" in pre else "cube-on-counter"
    valve = "valve-open" if "valve-open" in pre else "valve-closed"
    return frozenset({door, hand, cube, valve})


def episodes_for(
    spec: SkillSpec,
    rng: np.random.Generator,
    count: int = 8,
    end_shift: float = 0.0,
    end_facts: frozenset[str] | None = None,
) -> list[Episode]:
    """Successful episodes start -> end node (plus one failure that stops halfway)."""
    before = start_facts(spec)
    after = end_facts if end_facts is not None else (before - spec.del_effects) | spec.add_effects
    start = np.array(NODES[spec.start].position)
    end = np.array(NODES[spec.end].position) + np.array([0.0, 0.0, end_shift])
    episodes = []
    for i in range(count + 1):
        success = i < count
        goal = end if success else (start + end) / 2
        path = np.linspace(start, goal, STEPS + 1) + rng.normal(0.0, 0.003, (STEPS + 1, 3))
        obs = np.zeros((STEPS + 1, 10), dtype=np.float32)
        obs[:, :3] = path
        worlds = np.array(
            [world_for(before).as_array()] * (STEPS - 1)
            + [world_for(after if success else before).as_array()]
        )
        rewards = np.zeros(STEPS, dtype=np.float32)
        rewards[-1] = float(success)
        episodes.append(
            Episode(
                observations=obs[:-1],
                next_observations=obs[1:],
                actions=np.zeros((STEPS, 7), dtype=np.float32),
                rewards=rewards,
                terminations=rewards > 0,
                truncations=rewards == 0,
                world_states=worlds.astype(np.float32),
            )
        )
    return episodes


def write_data(
    folder: Path, skills: tuple[SkillSpec, ...] = SKILLS, **tweaks: dict[str, Any]
) -> Path:
    """One HDF5 data set per skill; ``tweaks[name]`` are ``episodes_for`` keyword arguments."""
    rng = np.random.default_rng(0)
    for spec in skills:
        options = tweaks.get(spec.name.replace("-", "_"), {})
        write_episodes(
            folder / f"{spec.name}.h5",
            episodes_for(spec, rng, **options),
            {"skill": spec.to_json(), "seed": 0, "world_fields": WORLD},
        )
    return folder


def load_all(folder: Path) -> list[Dataset]:
    return [load_dataset(path) for path in sorted(folder.glob("*.h5"))]


def test_world_for_round_trips_every_skill_world() -> None:
    for spec in SKILLS:
        before = start_facts(spec)
        after = (before - spec.del_effects) | spec.add_effects
        for facts in (before, after):
            state = world_state_from_array(world_for(facts).as_array())
            assert world_facts(state) == facts, spec.name


def test_graph_from_specs() -> None:
    graph = graph_from_specs(KITCHEN)
    assert graph.node_names == tuple(NODES)
    assert [e.name for e in graph.edges] == [s.name for s in SKILLS]
    assert graph.disagreements == ()
    slide = graph.edge("slide-door-open")
    assert slide.add_effects == ("door-open",)
    assert slide.del_effects == ("door-closed",)
    release = graph.edge("release-handle")
    assert (release.start, release.end) == ("handle-open", "cabinet-front")
    assert release.add_effects == ("hand-empty",)
    assert release.del_effects == ("holding-handle",)


def test_rates_are_checked() -> None:
    assert (
        graph_from_specs(KITCHEN, success_rates={"grab-cube": 0.7}).edge("grab-cube").success_rate
        == 0.7
    )
    with pytest.raises(SkillSpecError, match="outside"):
        graph_from_specs(KITCHEN, success_rates={"grab-cube": 1.5})
    with pytest.raises(SkillSpecError, match="unknown skill"):
        graph_from_specs(KITCHEN, success_rates={"fly": 0.5})


def test_json_round_trip(tmp_path: Path) -> None:
    graph = graph_from_specs(KITCHEN, success_rates={"grab-cube": 0.8})
    save_graph(graph, tmp_path / "g.json")
    assert load_graph(tmp_path / "g.json") == graph


def test_json_errors_name_the_file(tmp_path: Path) -> None:
    with pytest.raises(DatasetError, match="not found"):
        load_graph(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{}")
    with pytest.raises(DatasetError, match=f"{bad}: not a skill graph"):
        load_graph(bad)
    data = graph_from_specs(KITCHEN).to_dict()
    data["edges"][0]["start"] = "attic"
    bad.write_text(json.dumps(data))
    with pytest.raises(DatasetError, match="unknown node 'attic'"):
        load_graph(bad)


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_data(tmp_path_factory.mktemp("data"))


def test_graph_from_data_agrees_with_specs(data_dir: Path, tmp_path: Path) -> None:
    graph = graph_from_datasets(KITCHEN, load_all(data_dir), success_rates={"grab-cube": 0.9})
    assert graph.disagreements == ()
    for node in graph.nodes:
        assert node.observed is not None and node.observed.position is not None
        assert np.linalg.norm(np.subtract(node.observed.position, node.position)) < 0.01
    for edge, spec in zip(graph.edges, SKILLS, strict=True):
        assert edge.observed is not None and edge.observed.points == 8
        assert set(edge.observed.add) == spec.add_effects
        assert set(edge.observed.delete) == spec.del_effects
    assert graph.edge("grab-cube").success_rate == 0.9
    save_graph(graph, tmp_path / "g.json")
    assert load_graph(tmp_path / "g.json") == graph


def test_wrong_effects_and_regions_are_reported(tmp_path: Path) -> None:
    grab = next(s for s in SKILLS if s.name == "grab-cube")
    data = write_data(
        tmp_path,
        grab_cube={"end_facts": start_facts(grab)},  # the grasp never registers
        pick_up_cube={"end_shift": 0.10},  # ends 10 cm above cube-lifted
    )
    graph = graph_from_datasets(KITCHEN, load_all(data))
    issues = {(d.kind, d.subject): d.detail for d in graph.disagreements}
    assert "holding-cube" in issues[("effects", "grab-cube")]
    assert "not seen in data" in issues[("effects", "grab-cube")]
    assert ("region", "pick-up-cube") in issues
    assert any(kind == "node" for kind, _ in issues)
    assert ("no-data", "grab-cube") not in issues


def test_missing_skill_and_duplicates(tmp_path: Path) -> None:
    data = write_data(tmp_path, skills=SKILLS[:3])
    graph = graph_from_datasets(KITCHEN, load_all(data))
    missing = {d.subject for d in graph.disagreements if d.kind == "no-data"}
    assert missing == {s.name for s in SKILLS[3:]}
    empty = tmp_path / "empty" / "grab-cube.h5"
    write_episodes(empty, [], {"skill": SKILLS[8].to_json(), "seed": 0, "world_fields": WORLD})
    graph = graph_from_datasets(KITCHEN, [load_dataset(empty)])
    assert any(d.detail == f"{empty} has no episodes" for d in graph.disagreements)
    with pytest.raises(DatasetError, match="already read"):
        graph_from_datasets(KITCHEN, load_all(data) * 2)
    with pytest.raises(DatasetError, match="no data sets"):
        graph_from_datasets(KITCHEN, [])


def test_draw_png(tmp_path: Path) -> None:
    graph = graph_from_specs(KITCHEN)
    draw_graph(graph, tmp_path / "g.png", "xz")
    assert (tmp_path / "g.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="projection"):
        draw_graph(graph, tmp_path / "h.png", "zz")


def test_cli_graph(data_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rates = tmp_path / "rates.json"
    rates.write_text(json.dumps({"grab-cube": 0.75}))
    out, png = tmp_path / "graph.json", tmp_path / "graph.png"
    argv = [
        "graph",
        "--data",
        str(data_dir),
        "--rates",
        str(rates),
        "--out",
        str(out),
        "--png",
        str(png),
        "--json",
    ]
    assert main(argv) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads(out.read_text())
    assert printed["disagreements"] == [] and png.is_file()
    assert load_graph(out).edge("grab-cube").success_rate == 0.75
    assert main(["graph"]) == 0
    assert f"{len(NODES)} nodes, {len(SKILLS)} skills" in capsys.readouterr().out
    assert main(["plan", "--goal", "cube-lifted", "--graph", str(out), "--json"]) == 0
    costs = {s["action"]: s["cost"] for s in json.loads(capsys.readouterr().out)["steps"]}
    assert costs["grab-cube cube-1"] == 288  # round(-ln 0.75 * 1000)
