"""A goal: world facts to reach and, optionally, the graph node to end at (``(at NODE)``).

The planner reads ``(at NODE)`` atoms; the executor and the scoring must read them too, or
an execution that drove the robot to the node was reported failed because ``(at`` is not a
world fact. ``Goal.holds`` decides from the state handed to it: percepts in the executor,
the simulator's truth where an episode is scored.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from osg_control.domain.base import Domain
from osg_control.domain.lifted import AT
from osg_control.errors import PlanningError
from osg_control.execution.locate import node_at
from osg_control.planning.pddl_io import parse_atoms


@dataclass(frozen=True)
class Goal:
    """World facts to reach and the node to end at (None: anywhere)."""

    facts: frozenset[str]
    node: str | None = None

    def atoms(self) -> list[str]:
        """The goal as the planner reads it."""
        return sorted(self.facts) + ([] if self.node is None else [f"(at {self.node})"])

    def missing(
        self,
        domain: Domain,
        facts: Iterable[str],
        obs: np.ndarray,
        offsets: Mapping[str, np.ndarray] | None = None,
    ) -> list[str]:
        """What of the goal does not hold in ``facts`` and the TCP state ``obs``."""
        facts = set(facts)
        missing = sorted(self.facts - facts)
        if self.node is not None and node_at(domain, obs, facts, dict(offsets or {})) != self.node:
            missing.append(f"(at {self.node})")
        return missing

    def holds(
        self,
        domain: Domain,
        facts: Iterable[str],
        obs: np.ndarray,
        offsets: Mapping[str, np.ndarray] | None = None,
    ) -> bool:
        """Whether every fact holds and the TCP is on the goal's node."""
        return not self.missing(domain, facts, obs, offsets)


def parse_goal(goal: Any, domain: Domain) -> Goal:
    """A goal given as a string of atoms (``"door-open (at home)"``) or a collection of them.

    Atoms over the domain's objects (``(in-cabinet cube-1)``) are read as its facts
    (``cube-in-cabinet``); a declared fact's name may be written bare or as ``(name)``.

    Raises:
        ValueError: not strings, unreadable atoms, an unknown predicate, object or node, a
            wrong arity, or two nodes.
    """
    if not isinstance(goal, str):
        if not isinstance(goal, Iterable):
            raise ValueError(f"goal must be a collection of facts, got {goal!r}")
        goal = list(goal)
        if not all(isinstance(item, str) for item in goal):
            raise ValueError(f"goal must hold fact names (strings), got {goal!r}")
    try:
        atoms = parse_atoms(goal)
    except PlanningError as err:
        raise ValueError(f"goal: {err}") from None
    nodes = [atom[1] for atom in atoms if len(atom) == 2 and atom[0] == AT]
    if len(nodes) > 1:
        raise ValueError(f"goal atoms may name one (at NODE), got {len(nodes)}")
    if nodes and nodes[0] not in domain.nodes:
        raise ValueError(f"goal (at {nodes[0]}): unknown node; the nodes: {list(domain.nodes)}")
    facts = set()
    for atom in atoms:
        if len(atom) == 2 and atom[0] == AT:
            continue
        try:
            facts.add(domain.lifting.ground_fact("(" + " ".join(atom) + ")"))
        except PlanningError as err:
            raise ValueError(f"goal: {err}") from None
    return Goal(frozenset(facts), nodes[0] if nodes else None)
