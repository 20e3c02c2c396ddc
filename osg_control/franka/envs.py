"""FrankaKitchen-v1 envs for the domain: the adapter around a caller's env or a new one,
with its perception, and the D4RL benchmark's protocol (``BENCHMARK``)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from osg_control.domain.benchmark import Benchmark
from osg_control.domain.spec import SkillSpec
from osg_control.environment.options import Bounds
from osg_control.errors import DomainError
from osg_control.franka.arm import FrankaConfig
from osg_control.franka.domain import (
    FACTS,
    NODES,
    SETUPS,
    SKILLS,
    TASK_FACTS,
    facts_of,
    world_of,
)
from osg_control.franka.perception import PERCEPTIONS
from osg_control.json_files import parse_json
from osg_control.perception.spec import PerceptionSpec, check_supported

STEP_LIMIT = 280
"""FrankaKitchen-v1's registered episode limit (D4RL's protocol)."""
UNLIMITED_STEPS = 100_000
"""The env's limit in the no-limit variant (the executor's own budgets end it first)."""
GOAL_SETS: dict[str, tuple[str, ...]] = {
    "kitchen-complete": ("microwave", "kettle", "light switch", "slide cabinet"),
    "kitchen-mixed": ("microwave", "kettle", "bottom burner", "light switch"),
    "all-seven": tuple(TASK_FACTS),
}
"""D4RL's goal sets (kitchen-complete and kitchen-partial share theirs) and all seven."""
OWN_KWARGS = ("tasks_to_complete", "render_mode", "max_episode_steps")
"""``gymnasium.make`` options ``make_franka_env`` sets from its own arguments."""


def franka_perception(spec: PerceptionSpec | None) -> PerceptionSpec:
    """The adapter's perception for a core perception: None -> ``env`` (the default);
    ``env`` and ``sim`` as they are; ``paper`` (the core's ``EnvConfig`` default) -> ``env``
    with the paper's TCP noise (the env's own observation plus that noise).

    Raises:
        UsageError: a perception the domain does not support (``robot``), naming those it
            does.
    """
    if spec is None:
        return PerceptionSpec(PERCEPTIONS[0])
    if spec.name == "paper":
        return PerceptionSpec("env", tcp_noise=spec.tcp_noise)
    check_supported(spec, PERCEPTIONS, "franka-kitchen")
    return spec


def franka_config(config: Any = None, perception: PerceptionSpec | None = None) -> FrankaConfig:
    """A ``FrankaConfig`` from a ``FrankaConfig``, the core's ``EnvConfig`` (its
    perception translated by ``franka_perception``) or None; ``perception`` overrides."""
    if config is None:
        config = FrankaConfig()
    elif not isinstance(config, FrankaConfig):
        config = FrankaConfig(perception=franka_perception(getattr(config, "perception", None)))
    if perception is not None:
        config = replace(config, perception=franka_perception(perception))
    return config


ENV_OPTIONS: dict[str, Bounds | type[bool]] = {
    "robot_noise_ratio": Bounds(0.0, 1.0),
    "object_noise_ratio": Bounds(0.0, 1.0),
    "terminate_on_tasks_completed": bool,
    "remove_task_when_completed": bool,
}
"""The FrankaKitchen-v1 options ``env_kwargs`` may set, with their ranges: the noise ratios
scale the env's own observation noise (1e300 or NaN made every observation non-finite).
``frame_skip`` is not among them: the library asserts its control period against its
render rate, so only its default (40) runs (0 or 20 crash inside the library)."""


def check_env_kwargs(env_kwargs: Mapping[str, Any]) -> None:
    """Refuse an env option FrankaKitchen-v1 does not take here, or a value out of range.

    Raises:
        DomainError: naming the key (the options set from the other arguments, and the
            known ones, listed) and the value's range.
    """
    clash = sorted(set(env_kwargs) & set(OWN_KWARGS))
    if clash:
        raise DomainError(
            f"franka-kitchen: env_kwargs may not set {clash} (given as the task list, the "
            f"render mode and the step limit)"
        )
    for key, value in env_kwargs.items():
        rule = ENV_OPTIONS.get(key)
        if rule is None:
            raise DomainError(
                f"franka-kitchen: unknown env_kwargs key {key!r}; the known ones: "
                f"{', '.join(ENV_OPTIONS)}"
            )
        if rule is bool:
            if not isinstance(value, bool):
                raise DomainError(f"franka-kitchen: env_kwargs {key!r} must be true or false")
        elif isinstance(rule, Bounds) and not rule.admits(value):
            raise DomainError(
                f"franka-kitchen: env_kwargs {key!r} must be {rule.describe()}, got {value!r}"
            )


def make_franka_env(
    skill: SkillSpec | str | None = None,
    config: Any = None,
    render_mode: str | None = None,
    env: Any = None,
    tasks: list[str] | None = None,
    max_episode_steps: int | None = None,
    step_limit: int | None = None,
    perception: PerceptionSpec | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
) -> Any:
    """A ``FrankaKitchenAdapter`` around ``env`` (a caller's env must track ``tasks``, if
    given; default: a new FrankaKitchen-v1 with ``tasks``, all seven if not given, the
    registered 280-step limit unless ``max_episode_steps``, and the env's own options
    ``env_kwargs``, e.g. ``robot_noise_ratio``). ``config``: see ``franka_config``;
    ``perception`` (``env``, the default, or ``sim``) overrides the config's;
    ``step_limit``: the adapter's own limit, counted from the start (see the adapter).

    Raises:
        DomainError: an unknown task, a caller's env lacking one, or ``env_kwargs`` that
            set what the other arguments set, are unknown or out of range
            (``check_env_kwargs``).
        UsageError: an unsupported perception.
    """
    from osg_control.franka.compat import prepare
    from osg_control.franka.env import FrankaKitchenAdapter, check_kitchen

    config = franka_config(config, perception)
    prepare()
    unknown = sorted(set(tasks or ()) - set(TASK_FACTS))
    if unknown:
        raise DomainError(
            f"franka-kitchen: unknown task(s) {unknown}; the library's tasks: {sorted(TASK_FACTS)}"
        )
    check_env_kwargs(env_kwargs or {})
    if env is None:
        import gymnasium

        kwargs: dict[str, Any] = dict(env_kwargs or {})
        kwargs["tasks_to_complete"] = list(tasks or TASK_FACTS)
        if render_mode is not None:
            kwargs["render_mode"] = render_mode
        if max_episode_steps is not None:
            kwargs["max_episode_steps"] = max_episode_steps
        env = gymnasium.make("FrankaKitchen-v1", **kwargs)
    elif tasks:
        configured = set(getattr(check_kitchen(env), "goal", {}))
        lacking = sorted(set(tasks) - configured)
        if lacking:
            raise DomainError(
                f"franka-kitchen: the env given lacks task(s) {lacking} (its tasks: "
                f"{sorted(configured)}); make it with gymnasium.make('FrankaKitchen-v1', "
                f"tasks_to_complete=[...]) listing them"
            )
    spec = {s.name: s for s in SKILLS}[skill] if isinstance(skill, str) else skill
    return FrankaKitchenAdapter(
        env,
        NODES,
        world_of,
        facts_of,
        skill=spec,
        config=config,
        step_limit=step_limit,
        setups=SETUPS,
        world_facts=FACTS,
    )


def make_benchmark_env(
    tasks: tuple[str, ...],
    step_limit: int | None,
    noise: float = 0.0,
    start_steps: int = 0,
    perception: PerceptionSpec | None = None,
    env_kwargs: str | Mapping[str, Any] | None = None,
) -> Any:
    """The benchmark's env: FrankaKitchen-v1 for ``tasks``; with ``step_limit`` and no
    ``start_steps`` exactly the registered env (its own 280-step ``TimeLimit``), else one
    whose own limit leaves ``start_steps`` for the drive to a perturbed start, the adapter
    counting ``step_limit`` from the start. ``perception`` (default ``env``) with the
    paper's TCP ``noise`` [m] if given; ``env_kwargs``: the env's own options (a mapping
    or its JSON)."""
    if step_limit is None:
        max_steps: int | None = UNLIMITED_STEPS
    else:
        max_steps = step_limit + start_steps if start_steps else None
    spec = franka_perception(perception)
    if noise:
        spec = PerceptionSpec(spec.name, tcp_noise=noise)
    if isinstance(env_kwargs, str):
        env_kwargs = parse_json(env_kwargs) if env_kwargs else None
    return make_franka_env(
        config=FrankaConfig(perception=spec),
        tasks=list(tasks),
        max_episode_steps=max_steps,
        step_limit=step_limit if start_steps else None,
        env_kwargs=env_kwargs,
    )


BENCHMARK = Benchmark(
    name="D4RL kitchen (FrankaKitchen-v1)",
    goal_sets=GOAL_SETS,
    default_set="kitchen-complete",
    task_facts={task: pair[0] for task, pair in TASK_FACTS.items()},
    step_limit=STEP_LIMIT,
    make_env=make_benchmark_env,
    check_env_kwargs=check_env_kwargs,
    published={
        "BC": {"kitchen-complete": 65.0, "kitchen-mixed": 51.5},
        "CQL": {"kitchen-complete": 43.8, "kitchen-mixed": 51.0},
        "IQL": {"kitchen-complete": 62.5, "kitchen-mixed": 51.0},
        "TD3+BC": {"kitchen-complete": 0.0, "kitchen-mixed": 0.0},
    },
    published_note="monolithic offline RL trained on D4RL's human demonstrations (TD3+BC: "
    "about 0, one implementation, d3rlpy); ours: a skill graph trained on our own scripted "
    "data for the same tasks, metric and 280-step limit",
)
