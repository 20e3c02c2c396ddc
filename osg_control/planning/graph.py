"""The skill graph: nodes (TCP regions) and skill edges with effects, from the specs or from data.

The planner only needs the symbolic part (edges, pre/effects, success rates); the data-driven
build checks the specs against what the recorded episodes actually show and lists every
disagreement instead of failing, so a reviewer can decide which side is wrong.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from osg_control.domain.base import Domain
from osg_control.domain.spec import SkillSpec
from osg_control.errors import DatasetError, SkillSpecError
from osg_control.io_safety import atomic_write
from osg_control.json_files import is_json_number, read_json_object

if TYPE_CHECKING:  # the data-set module (h5py) loads only with data
    pass

GRAPH_FORMAT = "osg-skill-graph"
GRAPH_VERSION = 1
MATCH_RADIUS = 0.03
"""A cluster centre farther than this from every spec node is a disagreement [m]."""
CLUSTER_DISTANCE = 0.03
"""Average-linkage cut: clusters whose mean point distance exceeds this stay apart [m]."""
MAX_POINTS_PER_SET = 200
"""Start or end positions kept per skill for clustering (a seeded subsample beyond that)."""
EFFECT_VOTE = 0.5
"""Fraction of successful episodes in which a fact must change to count as an effect."""


@dataclass(frozen=True)
class Observed:
    """What the data says about a node or a skill's effects.

    Attributes:
        position: mean TCP position of the matched cluster [m] (nodes only).
        points: start/end positions in that cluster (nodes) or successful episodes (skills).
        add: facts the episodes made true (skills only).
        delete: facts the episodes made false (skills only).
    """

    position: tuple[float, float, float] | None = None
    points: int = 0
    add: tuple[str, ...] = ()
    delete: tuple[str, ...] = ()


@dataclass(frozen=True)
class GraphNode:
    """A region of the skill graph, named after its spec node."""

    name: str
    position: tuple[float, float, float]
    gripper: str = "open"
    observed: Observed | None = None


@dataclass(frozen=True)
class SkillEdge:
    """A skill as a graph edge: start node -> end node, world pre/effects, success rate."""

    name: str
    start: str
    end: str
    preconditions: tuple[str, ...] = ()
    add_effects: tuple[str, ...] = ()
    del_effects: tuple[str, ...] = ()
    success_rate: float | None = None
    observed: Observed | None = None
    step_cost: int = 0
    """Plan cost for the skill's duration (``Domain.step_cost`` x its step budget), added
    to its success-rate cost."""


@dataclass(frozen=True)
class Disagreement:
    """One place where the data contradicts the specs.

    Attributes:
        kind: ``node`` (cluster/spec node mismatch), ``region`` (a skill starts or ends
            elsewhere than its spec says), ``effects`` or ``no-data``.
        subject: the node or skill concerned.
        detail: a sentence for people.
    """

    kind: str
    subject: str
    detail: str


@dataclass(frozen=True)
class SkillGraph:
    """Nodes, skill edges and world facts; what the PDDL domain is generated from."""

    nodes: tuple[GraphNode, ...]
    edges: tuple[SkillEdge, ...]
    facts: tuple[str, ...] = ()
    disagreements: tuple[Disagreement, ...] = field(default=())

    @property
    def node_names(self) -> tuple[str, ...]:
        """The node names, in order."""
        return tuple(node.name for node in self.nodes)

    def edge(self, name: str) -> SkillEdge:
        """The edge of a named skill.

        Raises:
            KeyError: no edge has that name.
        """
        for edge in self.edges:
            if edge.name == name:
                return edge
        raise KeyError(f"no skill {name!r} in the graph; skills: {[e.name for e in self.edges]}")

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (see ``save_graph``)."""
        return {"format": GRAPH_FORMAT, "version": GRAPH_VERSION, **asdict(self)}


def step_budget(spec: SkillSpec) -> int:
    """A skill's Algorithm 1 step budget: the sum of its waypoints' budgets."""
    return sum(spec.waypoint_budgets())


def _edge_from_spec(spec: SkillSpec, success_rate: float | None, step_cost: float) -> SkillEdge:
    return SkillEdge(
        name=spec.name,
        start=spec.start,
        end=spec.end,
        preconditions=tuple(sorted(spec.preconditions)),
        add_effects=tuple(sorted(spec.add_effects)),
        del_effects=tuple(sorted(spec.del_effects)),
        success_rate=success_rate,
        step_cost=round(step_cost * step_budget(spec)),
    )


def _checked_rates(domain: Domain, success_rates: Mapping[str, float] | None) -> dict[str, float]:
    rates = dict(success_rates or {})
    for name, rate in rates.items():
        domain.skill(name)
        if not 0.0 <= rate <= 1.0:
            raise SkillSpecError(f"skill {name!r}: success rate {rate} is outside [0, 1]")
    return rates


def graph_from_specs(
    domain: Domain,
    skills: Sequence[SkillSpec] | None = None,
    success_rates: Mapping[str, float] | None = None,
) -> SkillGraph:
    """Build the graph from the skill specs alone (no data needed).

    Args:
        domain: the domain whose nodes and facts the graph has.
        skills: the skills to include (default: all the domain's).
        success_rates: measured success rate per skill name (optional, each in [0, 1]).

    Returns:
        The graph with one node per spec node used by a skill.

    Raises:
        SkillSpecError: a rate names an unknown skill or lies outside [0, 1].
    """
    rates = _checked_rates(domain, success_rates)
    skills = domain.skills if skills is None else skills
    used = {name for spec in skills for name in (spec.start, spec.end)}
    nodes = tuple(
        GraphNode(node.name, node.position, node.gripper)
        for node in domain.nodes.values()
        if node.name in used
    )
    edges = tuple(_edge_from_spec(spec, rates.get(spec.name), domain.step_cost) for spec in skills)
    return SkillGraph(nodes=nodes, edges=edges, facts=domain.facts)


def as_xyz(values: Iterable[float]) -> tuple[float, float, float]:
    x, y, z = (float(v) for v in values)
    return (x, y, z)


def _observed_from(data: Mapping[str, Any] | None) -> Observed | None:
    if data is None:
        return None
    position = data.get("position")
    return Observed(
        position=None if position is None else as_xyz(position),
        points=int(data.get("points", 0)),
        add=tuple(data.get("add", ())),
        delete=tuple(data.get("delete", ())),
    )


def graph_from_dict(data: Mapping[str, Any], source: str = "<graph>") -> SkillGraph:
    """Rebuild a graph from ``SkillGraph.to_dict`` output.

    Args:
        data: the dictionary.
        source: named in error messages (e.g. the file path).

    Returns:
        The graph.

    Raises:
        DatasetError: wrong format tag or version, or a missing or malformed field.
    """
    if data.get("format") != GRAPH_FORMAT or data.get("version") != GRAPH_VERSION:
        raise DatasetError(
            f"{source}: not a skill graph (expected format {GRAPH_FORMAT!r} version "
            f"{GRAPH_VERSION}, got {data.get('format')!r} version {data.get('version')!r})"
        )
    try:
        nodes = tuple(
            GraphNode(
                name=n["name"],
                position=as_xyz(n["position"]),
                gripper=n.get("gripper", "open"),
                observed=_observed_from(n.get("observed")),
            )
            for n in data["nodes"]
        )
        edges = tuple(
            SkillEdge(
                name=e["name"],
                start=e["start"],
                end=e["end"],
                preconditions=tuple(e.get("preconditions", ())),
                add_effects=tuple(e.get("add_effects", ())),
                del_effects=tuple(e.get("del_effects", ())),
                success_rate=e.get("success_rate"),
                observed=_observed_from(e.get("observed")),
                step_cost=int(e.get("step_cost", 0)),
            )
            for e in data["edges"]
        )
        facts = tuple(data["facts"])
        disagreements = tuple(Disagreement(**d) for d in data.get("disagreements", ()))
    except (KeyError, TypeError, IndexError, ValueError, OverflowError) as err:
        raise DatasetError(f"{source}: missing or malformed field: {err!r}") from err
    _check_references(nodes, edges, facts, source)
    return SkillGraph(nodes=nodes, edges=edges, facts=facts, disagreements=disagreements)


def _check_references(
    nodes: Sequence[GraphNode], edges: Sequence[SkillEdge], facts: Sequence[str], source: str
) -> None:
    node_names = {node.name for node in nodes}
    for edge in edges:
        for end in (edge.start, edge.end):
            if end not in node_names:
                raise DatasetError(f"{source}: skill {edge.name!r} names unknown node {end!r}")
        unknown = sorted(set(edge.preconditions + edge.add_effects + edge.del_effects) - set(facts))
        if unknown:
            raise DatasetError(f"{source}: skill {edge.name!r} names unknown facts {unknown}")
        rate = edge.success_rate
        if rate is not None and not (is_json_number(rate) and 0.0 <= rate <= 1.0):
            raise DatasetError(f"{source}: skill {edge.name!r} success rate {rate} not in [0, 1]")
        if edge.step_cost < 0:
            raise DatasetError(f"{source}: skill {edge.name!r} step cost {edge.step_cost} < 0")


def save_graph(graph: SkillGraph, path: str | Path) -> None:
    """Write the graph as JSON (sorted keys, indented, so diffs stay readable)."""
    text = json.dumps(graph.to_dict(), indent=2, sort_keys=True) + "\n"
    atomic_write(path, lambda tmp: tmp.write_text(text))


def load_graph(path: str | Path) -> SkillGraph:
    """Read a graph written by ``save_graph``.

    Raises:
        DatasetError: the file is missing, not JSON or not a skill graph; names the file.
    """
    path = Path(path)
    data = read_json_object(path, "skill graph file", DatasetError)
    return graph_from_dict(data, source=str(path))
