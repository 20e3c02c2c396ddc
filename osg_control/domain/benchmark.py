"""An outside benchmark's protocol as domain data: goal sets of the env's own task names,
scored by the env's own completion report.

The core's ``osg evaluate benchmark`` (``osg_control.evaluation.benchmark``) runs episodes
from the env's own reset, plans for the goal set's facts, executes within the env's step
limit, and scores each episode by the tasks the env itself reports completed. A domain
without a ``Benchmark`` has no such verb.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from osg_control.errors import DomainError, lookup

BenchmarkEnvFactory = Callable[..., Any]
"""``make_env(tasks, step_limit, noise)``: an env of the domain (as ``Domain.make_env``'s)
whose episode ends after ``step_limit`` steps from its start (None: no limit beyond the
executor's own budgets) and whose ``completed_tasks()`` lists the env's own completed
tasks of this episode."""


@dataclass(frozen=True)
class Benchmark:
    """An outside benchmark on a domain's env.

    Attributes:
        name: shown in reports (e.g. the benchmark's and env's names).
        goal_sets: goal-set name -> the env's own task names (e.g. D4RL's kitchen-complete).
        default_set: the goal set run when none is named.
        task_facts: env task name -> the domain's fact that holds when it is done.
        step_limit: the env's episode limit in steps (the standard protocol's).
        make_env: the env factory (see ``BenchmarkEnvFactory``).
        points: the score of an episode that completes every task of its goal set; each
            task done is worth ``points / len(tasks)`` (D4RL's kitchen: 100, 25 per task).
        published: method -> goal set -> its published score, shown beside ours.
        published_note: where those figures come from and how their protocol differs.
        check_env_kwargs: refuses env options (``--env-kwargs``) the env does not take or
            values out of their range (``DomainError`` naming the key); None: the env
            takes none.
    """

    name: str
    goal_sets: Mapping[str, tuple[str, ...]]
    default_set: str
    task_facts: Mapping[str, str]
    step_limit: int
    make_env: BenchmarkEnvFactory
    points: float = 100.0
    published: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    published_note: str = ""
    check_env_kwargs: Callable[[Mapping[str, Any]], None] | None = None

    def check_options(self, env_kwargs: Mapping[str, Any] | None) -> None:
        """Refuse env options the env does not take (see ``check_env_kwargs``).

        Raises:
            DomainError: naming the key and its range.
        """
        if not env_kwargs:
            return
        if self.check_env_kwargs is None:
            raise DomainError(f"benchmark {self.name!r}: its env takes no env options")
        self.check_env_kwargs(env_kwargs)

    def tasks_of(self, goal_set: str) -> tuple[str, ...]:
        """The env tasks of a goal set.

        Raises:
            DomainError: an unknown goal set, listing the known ones.
        """
        return lookup(
            dict(self.goal_sets), goal_set, "goal set", lambda m: DomainError(f"benchmark: {m}")
        )

    def check_tasks(self, tasks: tuple[str, ...]) -> tuple[str, ...]:
        """``tasks`` if the env knows each of them.

        Raises:
            DomainError: naming the unknown ones and listing the env's tasks.
        """
        unknown = [t for t in tasks if t not in self.task_facts]
        if unknown or not tasks:
            raise DomainError(
                f"benchmark {self.name!r}: unknown task(s) {unknown or list(tasks)}; the env's "
                f"tasks: {sorted(self.task_facts)}"
            )
        return tasks

    def goal(self, tasks: tuple[str, ...]) -> tuple[str, ...]:
        """The domain facts that say every task of ``tasks`` is done."""
        return tuple(self.task_facts[t] for t in self.check_tasks(tasks))


def validate_benchmark(benchmark: Benchmark, facts: tuple[str, ...], where: str) -> None:
    """Check a benchmark's goal sets and facts against its domain's facts.

    Raises:
        DomainError: naming the field at fault.
    """
    if benchmark.default_set not in benchmark.goal_sets:
        raise DomainError(
            f"{where}: benchmark default_set {benchmark.default_set!r} is not one of its goal "
            f"sets {sorted(benchmark.goal_sets)}"
        )
    for name, tasks in benchmark.goal_sets.items():
        try:
            benchmark.check_tasks(tuple(tasks))
        except DomainError as err:
            raise DomainError(f"{where}: benchmark goal set {name!r}: {err}") from err
    unknown = sorted(set(benchmark.task_facts.values()) - set(facts))
    if unknown:
        raise DomainError(f"{where}: benchmark task_facts name unknown facts {unknown}")
    if benchmark.step_limit < 1 or not callable(benchmark.make_env):
        raise DomainError(f"{where}: benchmark needs step_limit >= 1 and a callable make_env")
