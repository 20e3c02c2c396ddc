"""Early stopping of batched skills: a skill stops training once its success on held-out
episodes stops improving, and keeps the weights of its best check.

Every ``check_every`` updates each skill still training is run on held-out episodes (the
pipeline's ``HeldOutCheck``). A check that matches or beats the skill's best so far makes
its weights the kept ones (a tie keeps the later, more trained weights); only a strictly
better check counts as an improvement. A skill stops after ``patience`` checks in a row
without one, or at the update budget. Measured on the kitchen (docs/learning.md): most
skills reach their final success within 2,000-3,000 of the 10,000 updates that a fixed
budget spends on every skill.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

CHECK_EPISODES = 50
"""Held-out episodes per skill per check by default (the full reproduction's)."""


@dataclass(frozen=True)
class EarlyStopping:
    """The stopping rule.

    Attributes:
        check_every: updates between held-out checks.
        patience: checks in a row without a strict improvement after which a skill stops.
    """

    check_every: int = 1000
    patience: int = 2

    def __post_init__(self) -> None:
        """Reject settings below 1.

        Raises:
            ValueError: naming the setting.
        """
        for name in ("check_every", "patience"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"early stopping: {name} must be an integer >= 1, got {value!r}")

    def to_json_dict(self) -> dict[str, Any]:
        """The rule as recorded in a checkpoint's ``train_config["early_stopping"]["rule"]``."""
        return asdict(self)


@dataclass
class SkillProgress:
    """One skill's held-out checks and which of them holds its kept weights.

    Attributes:
        checks: ``(updates, success rate)`` of every check so far.
        best_rate: the best rate checked (-1 before any check).
        best_updates: the updates of the kept weights (the latest check at ``best_rate``).
        checks_without_improvement: checks in a row not strictly above the best before them.
    """

    checks: list[tuple[int, float]] = field(default_factory=list)
    best_rate: float = -1.0
    best_updates: int = 0
    checks_without_improvement: int = 0

    def record(self, updates: int, rate: float) -> bool:
        """Record a check; True when the weights just checked become the kept ones."""
        self.checks.append((updates, rate))
        improved = rate > self.best_rate
        self.checks_without_improvement = 0 if improved else self.checks_without_improvement + 1
        if rate >= self.best_rate:
            self.best_rate, self.best_updates = rate, updates
            return True
        return False

    def stopped(self, rule: EarlyStopping) -> bool:
        """Whether the rule stops the skill after the checks so far."""
        return self.checks_without_improvement >= rule.patience

    def to_json_dict(self, rule: dict[str, Any], max_updates: int) -> dict[str, Any]:
        """The record a checkpoint keeps: the rule (with how the checks ran), the budget,
        every check and the kept one."""
        return {
            "rule": rule,
            "max_updates": max_updates,
            "checks": [[updates, rate] for updates, rate in self.checks],
            "kept_updates": self.best_updates,
            "kept_rate": self.best_rate,
        }
