"""The skill graph from recorded data: cluster start/end positions into nodes, read effects
from world states, and list every disagreement with the specs (``graph_from_datasets``).

The data-driven build checks the specs against what the recorded episodes actually show and
lists every disagreement instead of failing, so a reviewer can decide which side is wrong.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from osg_control.domain.base import Domain
from osg_control.domain.spec import Node, SkillSpec, skill_from_json
from osg_control.errors import DatasetError, SkillSpecError
from osg_control.planning.graph import (
    CLUSTER_DISTANCE,
    EFFECT_VOTE,
    MATCH_RADIUS,
    MAX_POINTS_PER_SET,
    Disagreement,
    Observed,
    SkillEdge,
    SkillGraph,
    as_xyz,
    graph_from_specs,
)

if TYPE_CHECKING:  # the data-set module (h5py) loads only with data
    from osg_control.data.datasets import Dataset


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
            observed[node] = Observed(as_xyz(centres[k]), int(counts[k]))
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
