"""The skill graph: nodes (TCP regions) and skill edges with effects, from the specs or from data.

The planner only needs the symbolic part (edges, pre/effects, success rates); the data-driven
build checks the specs against what the recorded episodes actually show and lists every
disagreement instead of failing, so a reviewer can decide which side is wrong.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from osg_control.domain.base import Domain
from osg_control.domain.spec import Node, SkillSpec, skill_from_json
from osg_control.errors import DatasetError, SkillSpecError

if TYPE_CHECKING:  # the data-set module (h5py) loads only with data
    from osg_control.data.datasets import Dataset

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


def _edge_from_spec(spec: SkillSpec, success_rate: float | None) -> SkillEdge:
    return SkillEdge(
        name=spec.name,
        start=spec.start,
        end=spec.end,
        preconditions=tuple(sorted(spec.preconditions)),
        add_effects=tuple(sorted(spec.add_effects)),
        del_effects=tuple(sorted(spec.del_effects)),
        success_rate=success_rate,
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
    edges = tuple(_edge_from_spec(spec, rates.get(spec.name)) for spec in skills)
    return SkillGraph(nodes=nodes, edges=edges, facts=domain.facts)


@dataclass(frozen=True)
class _PointSet:
    skill: str
    role: str  # "start" or "end"
    node: str  # the spec node it should match
    points: np.ndarray


def _point_sets(
    dataset: Dataset, spec: SkillSpec, rng: np.random.Generator, match_radius: float
) -> list[_PointSet]:
    """The start and end positions that should form one cluster at a node each. Starts
    drawn over an initiation region wider than ``match_radius`` (movement skills start
    anywhere within 15 cm) scatter by design and are left out: they would split into many
    small clusters, each reported as a node disagreement."""
    starts = dataset.arrays["observations"][dataset.episode_starts, :3]
    ends = dataset.arrays["next_observations"][dataset.first_success_steps, :3]
    roles = [("start", spec.start, starts)] if spec.start_radius <= match_radius else []
    sets = []
    for role, node, found in (*roles, ("end", spec.end, ends)):
        points = np.asarray(found, dtype=float)
        if len(points) > MAX_POINTS_PER_SET:
            points = points[rng.choice(len(points), MAX_POINTS_PER_SET, replace=False)]
        if len(points):
            sets.append(_PointSet(spec.name, role, node, points))
    return sets


def _cluster(
    sets: Sequence[_PointSet], cluster_distance: float
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Average-linkage clusters of all points; returns cluster centres and per-set labels."""
    from scipy.cluster.hierarchy import fcluster, linkage  # here: planning never needs scipy

    points = np.concatenate([s.points for s in sets])
    if len(points) == 1:
        labels = np.zeros(1, dtype=int)
    else:
        labels = fcluster(linkage(points, "average"), cluster_distance, "distance") - 1
    centres = np.array([points[labels == k].mean(axis=0) for k in range(labels.max() + 1)])
    bounds = np.cumsum([0] + [len(s.points) for s in sets])
    return centres, [labels[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def _xyz(values: Iterable[float]) -> tuple[float, float, float]:
    x, y, z = (float(v) for v in values)
    return (x, y, z)


def _fmt(position: Iterable[float]) -> str:
    return "(" + ", ".join(f"{v:.3f}" for v in position) + ")"


def _match_regions(
    nodes: Mapping[str, Node],
    sets: Sequence[_PointSet],
    cluster_distance: float,
    match_radius: float,
) -> tuple[dict[str, Observed], list[Disagreement]]:
    """Cluster the start/end positions and match clusters to the spec nodes."""
    centres, labels = _cluster(sets, cluster_distance)
    names = list(nodes)
    spec_positions = np.array([nodes[name].position for name in names])
    distances = np.linalg.norm(centres[:, None, :] - spec_positions[None, :, :], axis=2)
    nearest = distances.argmin(axis=1)
    counts = np.bincount(np.concatenate(labels), minlength=len(centres))
    matched: dict[int, str] = {}
    issues = []
    for k, centre in enumerate(centres):
        node, gap = names[nearest[k]], distances[k, nearest[k]]
        if gap > match_radius:
            issues.append(
                Disagreement(
                    "node",
                    node,
                    f"cluster at {_fmt(centre)} ({counts[k]} points) is {gap * 100:.1f} cm "
                    f"from the nearest spec node {node!r} (limit {match_radius * 100:.0f} cm)",
                )
            )
        else:
            matched[k] = node
    observed: dict[str, Observed] = {}
    for k, node in matched.items():
        best = observed.get(node)
        if best is None or counts[k] > best.points:
            observed[node] = Observed(_xyz(centres[k]), int(counts[k]))
    for point_set, set_labels in zip(sets, labels, strict=True):
        found = sorted({matched.get(int(k), "no node") for k in set_labels})
        if found != [point_set.node]:
            issues.append(
                Disagreement(
                    "region",
                    point_set.skill,
                    f"{point_set.role} positions fall in {', '.join(found)}; "
                    f"spec says {point_set.node!r}",
                )
            )
    used = {s.node for s in sets}
    issues.extend(
        Disagreement(
            "node", name, f"spec node {name!r} has no cluster within {match_radius * 100:.0f} cm"
        )
        for name in names
        if name in used and name not in observed
    )
    return observed, issues


def _observed_effects(domain: Domain, dataset: Dataset) -> Observed:
    """Majority-vote add/delete effects over the successful episodes (first step vs the step
    that first reached beta)."""
    worlds = dataset.arrays["world_states"]
    firsts = dataset.episode_starts[dataset.episode_successes]
    lasts = dataset.first_success_steps
    added: dict[str, int] = {}
    deleted: dict[str, int] = {}
    for first, last in zip(firsts, lasts, strict=True):
        before = domain.facts_of(worlds[first])
        after = domain.facts_of(worlds[last])
        for fact in after - before:
            added[fact] = added.get(fact, 0) + 1
        for fact in before - after:
            deleted[fact] = deleted.get(fact, 0) + 1
    quorum = EFFECT_VOTE * len(firsts)
    return Observed(
        points=len(firsts),
        add=tuple(sorted(f for f, n in added.items() if n > quorum)),
        delete=tuple(sorted(f for f, n in deleted.items() if n > quorum)),
    )


def _effect_disagreement(edge: SkillEdge, observed: Observed) -> Disagreement | None:
    if observed.points == 0:
        return Disagreement("effects", edge.name, "no successful episode to derive effects from")
    diffs = []
    for label, spec, seen in (
        ("add", edge.add_effects, observed.add),
        ("del", edge.del_effects, observed.delete),
    ):
        if missing := sorted(set(spec) - set(seen)):
            diffs.append(f"spec {label} {missing} not seen in data")
        if extra := sorted(set(seen) - set(spec)):
            diffs.append(f"data {label} {extra} not in spec")
    if not diffs:
        return None
    return Disagreement(
        "effects", edge.name, f"{'; '.join(diffs)} ({observed.points} successful episodes)"
    )


def graph_from_datasets(
    domain: Domain,
    datasets: Sequence[Dataset],
    success_rates: Mapping[str, float] | None = None,
    cluster_distance: float = CLUSTER_DISTANCE,
    match_radius: float = MATCH_RADIUS,
    seed: int = 0,
) -> SkillGraph:
    """Build the graph from recorded data sets and report where they contradict the specs.

    Regions: the start TCP positions of all episodes and the end positions of the successful
    ones are clustered together (average linkage) and each cluster is matched to the nearest
    spec node. Effects: per skill, the facts that change between the first and the last step
    of a successful episode (majority vote). Edges keep the pre/effects of the spec each data
    set was recorded with (its ``skill`` attribute); what the data showed is stored beside
    them (``observed``) and every mismatch is a ``Disagreement``.

    Args:
        domain: the domain the data sets belong to (nodes, facts, the skills expected).
        datasets: one loaded data set per skill (``datasets.load_dataset``).
        success_rates: measured success rate per skill name (optional, each in [0, 1]).
        cluster_distance: average-linkage cut [m].
        match_radius: largest cluster-centre to spec-node distance that still matches [m].
        seed: seeds the subsample of large point sets.

    Returns:
        The graph over all the skills; skills without data are listed as ``no-data``.

    Raises:
        DatasetError: no data set, or two data sets for the same skill.
        SkillSpecError: a data set or rate names an unknown skill, a data set's recorded
            spec is unreadable, or a rate is out of range.
    """
    if not datasets:
        raise DatasetError("no data sets given to build the skill graph from")
    by_skill: dict[str, Dataset] = {}
    for dataset in datasets:
        name = dataset.skill_name
        if name in by_skill:
            raise DatasetError(
                f"{dataset.path}: skill {name!r} already read from {by_skill[name].path}"
            )
        domain.skill(name)
        by_skill[name] = dataset
    recorded = {name: _recorded_spec(d) for name, d in by_skill.items()}
    specs = [recorded.get(s.name, s) for s in domain.skills]
    usable = {name: d for name, d in by_skill.items() if d.num_episodes}
    graph = graph_from_specs(domain, specs, success_rates=success_rates)
    rng = np.random.default_rng(seed)
    sets = [
        s for name, d in usable.items() for s in _point_sets(d, recorded[name], rng, match_radius)
    ]
    observed_nodes, issues = (
        _match_regions(domain.nodes, sets, cluster_distance, match_radius) if sets else ({}, [])
    )
    edges = []
    for edge in graph.edges:
        if edge.name not in usable:
            where = (
                f"{by_skill[edge.name].path} has no episodes"
                if edge.name in by_skill
                else ("no data set for this skill")
            )
            issues.append(Disagreement("no-data", edge.name, where))
            edges.append(edge)
            continue
        observed = _observed_effects(domain, usable[edge.name])
        if (issue := _effect_disagreement(edge, observed)) is not None:
            issues.append(issue)
        edges.append(replace(edge, observed=observed))
    nodes = tuple(replace(node, observed=observed_nodes.get(node.name)) for node in graph.nodes)
    return replace(graph, nodes=nodes, edges=tuple(edges), disagreements=tuple(issues))


def _recorded_spec(dataset: Dataset) -> SkillSpec:
    """The spec a data set was recorded with (its ``skill`` attribute)."""
    try:
        return skill_from_json(str(dataset.attrs["skill"]))
    except SkillSpecError as err:
        raise SkillSpecError(f"{dataset.path}: recorded skill spec: {err}") from err


def _observed_from(data: Mapping[str, Any] | None) -> Observed | None:
    if data is None:
        return None
    position = data.get("position")
    return Observed(
        position=None if position is None else _xyz(position),
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
                position=_xyz(n["position"]),
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
            )
            for e in data["edges"]
        )
        facts = tuple(data["facts"])
        disagreements = tuple(Disagreement(**d) for d in data.get("disagreements", ()))
    except (KeyError, TypeError, IndexError, ValueError) as err:
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
        if rate is not None and not 0.0 <= rate <= 1.0:
            raise DatasetError(f"{source}: skill {edge.name!r} success rate {rate} not in [0, 1]")


def save_graph(graph: SkillGraph, path: str | Path) -> None:
    """Write the graph as JSON (sorted keys, indented, so diffs stay readable)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(graph.to_dict(), indent=2, sort_keys=True) + "\n")


def load_graph(path: str | Path) -> SkillGraph:
    """Read a graph written by ``save_graph``.

    Raises:
        DatasetError: the file is missing, not JSON or not a skill graph; names the file.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise DatasetError(f"{path}: skill graph file not found") from None
    except (OSError, json.JSONDecodeError) as err:
        raise DatasetError(f"{path}: not a readable JSON skill graph ({err})") from err
    if not isinstance(data, dict):
        raise DatasetError(f"{path}: expected a JSON object")
    return graph_from_dict(data, source=str(path))
