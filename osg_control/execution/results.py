"""What the executor works with and returns: the policy and classifier it is given, the
outcome of each option and the structured result of an execution (a stable JSON schema)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Protocol

import numpy as np

RESULT_SCHEMA_VERSION = 1
"""The version of ``ExecutionResult.to_dict``'s schema."""


class Policy(Protocol):
    """Maps a 10-D observation to a 7-D action."""

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        """The action for one observation."""
        ...


class EntryClassifier(Protocol):
    """Scores the movement skills that may bring a state onto the graph."""

    classes: tuple[str, ...]

    def predict_proba(self, states: np.ndarray, motion: np.ndarray | None = None) -> np.ndarray:
        """Class probabilities (in ``classes`` order) for one state and its motion input
        (``classifier.motion``; None: at rest)."""
        ...


@dataclass
class SkillOutcome:
    """What happened when one option ran."""

    skill: str
    success: bool
    steps: int
    seconds: float
    reset_steps: int = 0
    failure: str | None = None


@dataclass
class ExecutionResult:
    """The structured result of ``Executor.execute`` (stable JSON schema, see ``to_dict``)."""

    goal: list[str]
    success: bool
    entry_skill: str | None
    plan: list[str]
    outcomes: list[SkillOutcome] = field(default_factory=list)
    replans: int = 0
    failure: str | None = None
    final_facts: list[str] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (``schema_version`` first)."""
        return {"schema_version": RESULT_SCHEMA_VERSION, **asdict(self)}
