"""Seeded random skill graphs and goals, for the planner's benchmark and tests."""

from __future__ import annotations

import random
from dataclasses import dataclass, replace

from osg_control.domain.base import Domain
from osg_control.domain.lifted import ObjectInstance
from osg_control.errors import DomainError
from osg_control.planning.graph import GraphNode, SkillEdge, SkillGraph


@dataclass(frozen=True)
class RandomGoal:
    """A start (node and true facts) and a goal (atoms) over a random graph."""

    node: str
    world: tuple[str, ...]
    goal: tuple[str, ...]


def random_skill_graph(num_skills: int, num_facts: int = 4, seed: int = 0) -> SkillGraph:
    """A random skill graph: nodes on a ring (so all are connected) plus random skills.

    About a quarter as many nodes as skills (at least 3). Each skill moves between two nodes;
    some need a world fact, some add or delete one; success rates lie in [0.5, 1].

    Args:
        num_skills: skills (edges) to create, at least the node count.
        num_facts: world facts ``f0`` ... to use.
        seed: seeds everything.

    Returns:
        The graph.
    """
    rng = random.Random(seed)
    num_nodes = max(3, num_skills // 4)
    nodes = tuple(
        GraphNode(f"n{i}", (rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0, 1)))
        for i in range(num_nodes)
    )
    facts = tuple(f"f{i}" for i in range(num_facts))
    edges = []
    for i in range(num_skills):
        start = i % num_nodes if i < num_nodes else rng.randrange(num_nodes)
        end = (start + 1) % num_nodes if i < num_nodes else rng.randrange(num_nodes)

        def some(p: float) -> tuple[str, ...]:
            return (rng.choice(facts),) if facts and rng.random() < p else ()

        pre, add = some(0.2), some(0.3)
        delete = tuple(f for f in some(0.15) if f not in add)
        edges.append(
            SkillEdge(
                f"s{i}", f"n{start}", f"n{end}", pre, add, delete, round(rng.uniform(0.5, 1.0), 3)
            )
        )
    return SkillGraph(nodes=nodes, edges=tuple(edges), facts=facts)


def random_goal(graph: SkillGraph, seed: int = 0, num_goal_facts: int = 1) -> RandomGoal:
    """A random start and goal: reach another node with facts that are false at the start.

    Args:
        graph: the graph (from ``random_skill_graph``).
        seed: seeds the draw.
        num_goal_facts: world facts in the goal besides the target node.

    Returns:
        The start and goal (which may be unreachable).
    """
    rng = random.Random(seed)
    start, target = rng.sample(graph.node_names, 2)
    world = tuple(f for f in graph.facts if rng.random() < 0.3)
    false = [f for f in graph.facts if f not in world]
    wanted = rng.sample(false, min(num_goal_facts, len(false)))
    return RandomGoal(start, world, (f"(at {target})", *wanted))


def with_instances(domain: Domain, kind: str, count: int) -> Domain:
    """The domain with ``count`` instances of type ``kind`` (``KIND-1`` ... added to the
    ones it declares; the extra ones carry no frame): a synthetic N-object problem of its
    lifted skills, for planning only (its env still has its own objects).

    Raises:
        DomainError: ``kind`` is not one of its types.
        ValueError: ``count`` below the instances it already has of that type.
    """
    if kind not in domain.types:
        raise DomainError(f"domain {domain.name!r} has no type {kind!r}")
    have = domain.lifting.of_type(kind)
    if count < len(have):
        raise ValueError(f"domain {domain.name!r} already has {len(have)} {kind} instances")
    names = [f"{kind}-{i}" for i in range(1, count + 1) if f"{kind}-{i}" not in have]
    extra = tuple(ObjectInstance(name, kind) for name in names[: count - len(have)])
    return replace(domain, name=f"{domain.name}-{count}-{kind}", instances=domain.instances + extra)
