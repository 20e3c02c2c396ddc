"""``osg --domain libero VERB``: the LIBERO domain's own verbs (it is not a skill-graph
``Domain``: one operator is learned, the others scripted), registered through the
``osg_control.domain_verbs`` entry point. Importing this module imports no LIBERO code;
each verb checks its arguments (exit 2, nothing run), then needs the ``libero`` extra.

- ``pddl export --suite S [--task I ...] [--out DIR]``: the lifted domain ``osg-libero``
  and one PDDL problem per task file;
- ``plan --suite S --task I [--planner P] [--time-limit S] [--json]``: the plan for one
  task's goal (exit status as ``osg plan``'s);
- ``evaluate benchmark --suite S [--task I ...] [--episodes N | --init-states A:B]
  [--policy skills|scripted-plan] [--models DIR] [--seed K] [--workers W] [--json]``: the
  benchmark's protocol (``libero.benchmark``); without ``--policy`` it runs ``skills`` from
  the shipped skills folder, and refuses (``NoPolicyError``) where none is shipped;
- ``collect`` and ``train`` (``skill_verbs``): a skill's data and its training.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from osg_control.commands.plan import EPILOG, EXIT_STATUS, PLANNER_NAMES, format_plan
from osg_control.errors import OSGError, UsageError
from osg_control.libero import skill_verbs
from osg_control.libero.suites import INIT_STATES, max_steps, parse_init_states, suite_names


class NoPolicyError(OSGError):
    """No learned LIBERO skills to evaluate: none shipped, none given (exit 1)."""


POLICIES = ("skills", "scripted-plan")
"""The policies ``--policy`` runs: ``skills`` plans the task file's goal and runs it with
the learned skills for the operators they cover (``pick``, ``pick-out``) and scripted
controllers for the others (``skills.SkillsExecutor``); ``scripted-plan`` runs every
operator with its scripted controller (``executor.PlanExecutor``)."""
NO_POLICY = (
    "no learned LIBERO skills shipped in this install and no --models given "
    "(docs/libero.md: osg --domain libero collect, train); --policy scripted-plan runs "
    "the plans with scripted operator controllers instead; nothing was run"
)


PLAN_HELP = (
    "plan one task's goal, read from its task file, over the lifted domain osg-libero "
    "(--policy scripted-plan of evaluate benchmark runs such plans)"
)


def _suite_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--suite", required=True, help=f"the suite: {', '.join(suite_names())}")
    parser.add_argument(
        "--task", type=int, nargs="+", default=None, metavar="I",
        help="task indices in the suite (default: all)",
    )  # fmt: skip


def _sub_verb(
    subparsers: argparse._SubParsersAction, group: str, group_help: str, verb: str, **kw: str
) -> argparse.ArgumentParser:
    """``osg --domain libero GROUP VERB``'s parser (``GROUP`` as in the core's verbs)."""
    parser = subparsers.add_parser(group, help=group_help)
    verbs = parser.add_subparsers(dest=f"{group}_command", metavar="VERB", required=True)
    sub: argparse.ArgumentParser = verbs.add_parser(verb, **kw)
    return sub


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``pddl export``, ``plan`` and ``evaluate benchmark`` for the LIBERO domain."""
    export = _sub_verb(
        subparsers,
        "pddl",
        "export LIBERO's task files as PDDL problems",
        "export",
        help="write the lifted domain and one PDDL problem per task file of a suite",
        description="Write the lifted domain osg-libero (our operators, typed for the "
        "suite's categories) and each task's BDDL file as a PDDL problem of it (typed "
        "objects, init, goal).",
    )
    _suite_argument(export)
    export.add_argument(
        "--out", type=Path, default=None, help="output folder (default: ./domains/libero/SUITE)"
    )
    export.set_defaults(func=run_export)
    plan = subparsers.add_parser("plan", help=PLAN_HELP, description=PLAN_HELP, epilog=EPILOG)
    plan.add_argument("--suite", required=True, help=f"the suite: {', '.join(suite_names())}")
    plan.add_argument("--task", type=int, required=True, metavar="I", help="the task's index")
    plan.add_argument(
        "--planner", choices=PLANNER_NAMES, default="auto",
        help="search (default: auto, as osg plan's)",
    )  # fmt: skip
    plan.add_argument(
        "--time-limit", type=float, default=300.0, metavar="S",
        help="stop after S seconds with the answer unknown (default: 300)",
    )  # fmt: skip
    plan.add_argument("--json", action="store_true", help="print the result as JSON")
    plan.set_defaults(func=run_plan)
    bench = _sub_verb(
        subparsers,
        "evaluate",
        "the LIBERO benchmark",
        "benchmark",
        help="episodes from the tasks' fixed initial states, scored by check_success()",
    )
    _suite_argument(bench)
    episodes = bench.add_mutually_exclusive_group()
    episodes.add_argument(
        "--episodes", type=int, default=None,
        help=f"the first N initial states of each task (1-{INIT_STATES}; default all)",
    )  # fmt: skip
    episodes.add_argument(
        "--init-states", default=None, metavar="A:B",
        help=f"initial states A .. B-1 of each task (0 <= A < B <= {INIT_STATES})",
    )  # fmt: skip
    bench.add_argument(
        "--policy",
        default=None,
        metavar="NAME",
        help="what runs the episodes: skills (the default: plans the task file's goal, "
        "runs pick/pick-out with the learned skill and the other operators with scripted "
        "controllers, replanning from percepts) or scripted-plan (every operator scripted)",
    )
    bench.add_argument(
        "--models", type=Path, default=None, metavar="DIR",
        help="the skills folder of --policy skills (default: the shipped one)",
    )  # fmt: skip
    bench.add_argument(
        "--seed", type=int, default=0,
        help="seed of the fixture sensor's noise (initial state s draws from (seed, s))",
    )  # fmt: skip
    bench.add_argument("--workers", type=int, default=1)
    bench.add_argument("--json", action="store_true")
    bench.set_defaults(func=run_benchmark)
    skill_verbs.register(subparsers)


def run_export(args: argparse.Namespace) -> int:
    """Write the suite's problems (``pddl_export.export_problems``)."""
    max_steps(args.suite)  # an unknown suite: exit 2 before LIBERO is imported
    from osg_control.libero.pddl_export import export_problems
    from osg_control.libero.tasks import check_task_indices, task_problem

    indices = check_task_indices(args.suite, args.task)
    suite = [task_problem(args.suite, i) for i in check_task_indices(args.suite, None)]
    out = args.out or Path("domains") / "libero" / args.suite
    for path in export_problems([suite[i] for i in indices], out, typed_for=suite):
        print(f"wrote {path}")
    return 0


def run_plan(args: argparse.Namespace) -> int:
    """Plan the task's goal and print the plan (``plan.plan_task``); exit status as
    ``osg plan``'s (0 a plan, 3 none, 4 a limit), 2 for a goal predicate no operator
    achieves (named)."""
    max_steps(args.suite)
    if args.time_limit <= 0:
        raise UsageError(f"--time-limit must be positive, got {args.time_limit:g}")
    from osg_control.json_files import dump_json
    from osg_control.libero.plan import plan_task
    from osg_control.libero.tasks import check_task_indices, task_problem
    from osg_control.planning.task import SearchLimits

    (index,) = check_task_indices(args.suite, [args.task])
    problem = task_problem(args.suite, index)
    result = plan_task(problem, args.planner, SearchLimits(time_s=args.time_limit))
    if args.json:
        print(dump_json({**result.to_dict(), "suite": args.suite, "task": index,
                         "name": problem.name}))  # fmt: skip
    else:
        print(f"{args.suite} task {index}: {problem.name}")
        print(format_plan(result))
    return EXIT_STATUS[result.status]


def init_state_range(args: argparse.Namespace) -> range:
    """The initial states ``--episodes`` or ``--init-states`` ask for (default all).

    Raises:
        UsageError: more episodes than initial states, or a range outside them.
    """
    if args.init_states is not None:
        return parse_init_states(args.init_states)
    episodes = INIT_STATES if args.episodes is None else args.episodes
    if not 1 <= episodes <= INIT_STATES:
        raise UsageError(f"--episodes: each task has {INIT_STATES} initial states, got {episodes}")
    return range(episodes)


def run_benchmark(args: argparse.Namespace) -> int:
    """Check the arguments, then run ``--policy``'s episodes and print the summary; without
    ``--policy``, run ``skills`` from ``--models`` or the shipped folder, and refuse where
    there is none (``NoPolicyError``)."""
    max_steps(args.suite)
    states = init_state_range(args)
    if args.policy is not None and args.policy not in POLICIES:
        raise UsageError(f"--policy: unknown policy {args.policy!r}; known: {', '.join(POLICIES)}")
    if args.workers < 1:
        raise UsageError(f"--workers must be at least 1, got {args.workers}")
    from osg_control.libero.tasks import check_task_indices

    if args.models is not None and args.policy == "scripted-plan":
        raise UsageError("--models: the scripted-plan policy loads no skills")
    tasks = check_task_indices(args.suite, args.task)
    from osg_control.json_files import dump_json
    from osg_control.libero.benchmark import run_suite, summarise
    from osg_control.libero.executor import PlanExecutor
    from osg_control.libero.skills import learned_operators, shipped, skills_factory
    from osg_control.libero.training import DEFAULTS_DIR, read_manifest

    policy = args.policy or ("skills" if args.models is not None or shipped() else None)
    if policy is None:
        raise NoPolicyError(NO_POLICY)
    models = args.models or DEFAULTS_DIR
    factory = skills_factory(models) if policy == "skills" else PlanExecutor
    names = list(read_manifest(models)["skills"]) if policy == "skills" else []
    learned, scripted = learned_operators(names)
    episodes = run_suite(args.suite, tasks, list(states), factory, args.workers, args.seed)
    summary = summarise(args.suite, policy, episodes, args.seed)
    summary.update(operators_learned=learned, operators_scripted=scripted,
                   models=str(models) if names else None)  # fmt: skip
    if args.json:
        print(dump_json(summary))
        return 0
    for task, row in summary["tasks"].items():
        print(f"task {task}: {row['successes']}/{row['episodes']}")
    low, high = summary["interval_95"]
    kind = f"learned {', '.join(learned)}, scripted the rest" if learned else "scripted operators"
    print(
        f"{args.suite} ({summary['policy']}: {kind}): "
        f"{100 * summary['success_rate']:.1f} % of {summary['episodes']} episodes "
        f"[95 % {100 * low:.1f}-{100 * high:.1f}], at most {summary['max_steps']} steps each"
    )
    return 0
