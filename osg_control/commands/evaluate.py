"""``osg evaluate tasks`` (the paper's Tables IV and V over the domain's start regions) and
``osg evaluate benchmark`` (a domain's outside benchmark, scored by its env)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import Any

from osg_control.commands import (
    add_backend_arguments,
    add_filter_argument,
    add_perception_arguments,
    add_randomize_argument,
    camera_setups,
    domain_of,
    perception_of,
)
from osg_control.domain.base import Domain
from osg_control.evaluation.evaluate import format_task_table, task_table
from osg_control.evaluation.resume import source_fingerprint
from osg_control.execution.defaults import describe_models, models_fingerprint, models_in_use
from osg_control.io_safety import check_output_dir
from osg_control.json_files import JSONFormatError, dump_json, parse_json
from osg_control.parallel import open_executor
from osg_control.paths import cache_dir


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``evaluate`` (verb ``tasks``) to the ``osg`` parser."""
    evaluate = subparsers.add_parser("evaluate", help="full-pipeline evaluations")
    verbs = evaluate.add_subparsers(dest="evaluate_command", metavar="VERB", required=True)
    tasks = verbs.add_parser(
        "tasks", help="Tables IV and V: the domain's tasks from its start regions"
    )
    tasks.add_argument("--episodes", type=int, default=100, help="episodes per cell")
    tasks.add_argument(
        "--noise",
        type=float,
        default=None,
        help="the paper protocol's TCP observation noise [m] (default 0.02)",
    )
    add_perception_arguments(tasks)
    add_randomize_argument(tasks)
    tasks.add_argument("--seed", type=int, default=0)
    tasks.add_argument("--workers", type=int, default=2)
    add_backend_arguments(tasks)
    tasks.add_argument("--task", nargs="*", default=None, help="task names (default: all)")
    tasks.add_argument(
        "--replans",
        type=int,
        nargs="+",
        default=[0, 2],
        help="replanning budgets to compare (default: 0 and 2)",
    )
    tasks.add_argument("--models", type=Path, default=None, help="defaults directory")
    add_filter_argument(tasks)
    tasks.add_argument("--json", action="store_true")
    tasks.set_defaults(func=run_tasks)
    _register_benchmark(verbs)


def _register_benchmark(verbs: argparse._SubParsersAction) -> None:
    bench = verbs.add_parser(
        "benchmark",
        help="the domain's outside benchmark (e.g. D4RL kitchen-complete on FrankaKitchen-v1), "
        "scored by the env's own task completions",
    )
    bench.add_argument(
        "--set", dest="goal_set", default=None, help="goal set (default: the benchmark's)"
    )
    bench.add_argument(
        "--tasks", nargs="+", default=None, help="the env's task names (instead of --set)"
    )
    bench.add_argument("--episodes", type=int, default=100)
    bench.add_argument("--seed", type=int, default=0)
    bench.add_argument("--workers", type=int, default=2)
    add_backend_arguments(bench)
    bench.add_argument("--models", type=Path, default=None, help="defaults directory")
    bench.add_argument(
        "--noise", type=float, default=None, help="TCP observation noise [m] (default 0)"
    )
    add_perception_arguments(bench)
    bench.add_argument(
        "--env-kwargs",
        type=_json_object,
        default=None,
        metavar="JSON",
        help="the env's own constructor options, passed to gymnasium.make (e.g. "
        "'{\"robot_noise_ratio\": 0.02}')",
    )
    add_filter_argument(bench)
    bench.add_argument(
        "--perturbed",
        action="store_true",
        help="start from random poses in the domain's first start region (the drive there "
        "not counted) instead of the env's reset",
    )
    bench.add_argument(
        "--no-limit",
        action="store_true",
        help="no episode step limit (only the executor's own budgets)",
    )
    bench.add_argument("--max-replans", type=int, default=2)
    bench.add_argument("--json", action="store_true")
    bench.set_defaults(func=run_benchmark_command)


def run_benchmark_command(args: argparse.Namespace) -> int:
    """Print the benchmark score, its interval, per-task rates and steps used."""
    from osg_control.evaluation.benchmark import benchmark_of, format_benchmark, run_benchmark

    domain = domain_of(args)
    _check_benchmark_options(benchmark_of(domain), args)
    perception = perception_of(args, domain)
    resume_dir = evaluation_cache(domain, "benchmark", args.models)
    with open_executor(args.backend, args.workers, args.address) as executor:
        summary = run_benchmark(
            domain,
            goal_set=args.goal_set,
            tasks=args.tasks,
            episodes=args.episodes,
            seed=args.seed,
            models=str(args.models) if args.models else None,
            noise=0.0,  # the perception carries the TCP noise
            filter_gain=args.filter,
            perturbed=args.perturbed,
            limited=not args.no_limit,
            max_replans=args.max_replans,
            workers=args.workers,
            executor=executor,
            resume_dir=resume_dir,
            perception=perception,
            env_kwargs=args.env_kwargs,
        )
    return print_result(domain, args, summary, format_benchmark)


def _check_benchmark_options(bench: Any, args: argparse.Namespace) -> None:
    """``--set``, ``--tasks`` and ``--env-kwargs`` against the benchmark, before any work.

    Raises:
        UsageError: both ``--set`` and ``--tasks``, an unknown goal set or task, or an env
            option the env does not take (or out of its range); each named.
    """
    from osg_control.errors import DomainError, UsageError

    if args.tasks and args.goal_set is not None:
        raise UsageError("--tasks and --set exclude each other: give the goal set or its tasks")
    for option, check in (
        ("--tasks", lambda: args.tasks and bench.check_tasks(tuple(args.tasks))),
        ("--set", lambda: args.goal_set is not None and bench.tasks_of(args.goal_set)),
        ("--env-kwargs", lambda: bench.check_options(args.env_kwargs)),
    ):
        try:
            check()
        except DomainError as err:
            raise UsageError(f"{option}: {err}") from None


def _json_object(text: str) -> dict[str, Any]:
    """``--env-kwargs``: a JSON object, else a usage error naming the option."""
    try:
        value = parse_json(text)
    except JSONFormatError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
    if not isinstance(value, dict):
        raise argparse.ArgumentTypeError(f"must be a JSON object, got {text!r}")
    return value


def run_tasks(args: argparse.Namespace) -> int:
    """Print Tables IV and V."""
    domain = domain_of(args)
    perception = perception_of(args, domain, default_noise=0.02)
    resume_dir = evaluation_cache(domain, "tasks", args.models)
    with open_executor(args.backend, args.workers, args.address) as executor:
        table = task_table(
            domain,
            str(args.models) if args.models else None,
            args.episodes,
            args.seed,
            args.workers,
            args.task,
            args.replans,
            args.filter,
            executor,
            resume_dir=resume_dir,
            progress=not args.json,
            perception=perception,
            randomize=args.randomize_objects,
        )
    if perception.name == "camera":
        table["cameras"] = camera_setups(domain, perception)
    return print_result(domain, args, table, format_task_table)


def evaluation_cache(domain: Domain, kind: str, models: Path | None) -> Path:
    """Where an evaluation of ``kind`` over a defaults directory keeps finished episodes
    (resume), checked writable before the work."""
    fingerprint = f"{models_fingerprint(domain, models)}-{source_fingerprint()}"
    return check_output_dir(
        cache_dir() / domain.ref / "evaluation" / f"{kind}-{fingerprint}", "evaluation cache"
    )


def print_result(
    domain: Domain,
    args: argparse.Namespace,
    result: dict[str, Any],
    formatter: Callable[[dict[str, Any]], str],
) -> int:
    """Print an evaluation (JSON with ``--json``, else text), naming the models it used."""
    result["models"] = models_in_use(domain, args.models)
    print(dump_json(result) if args.json else formatter(result))
    if not args.json:
        print(describe_models(result["models"]))
    return 0
