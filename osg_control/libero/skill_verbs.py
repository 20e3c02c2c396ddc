"""``osg --domain libero collect`` and ``train``: Algorithm 1's data for a LIBERO operator
(``recording``) and the lifted skill trained on it (``training``). Importing this module
imports no LIBERO code; each verb checks its arguments (exit 2, nothing run) first.

- ``collect --suite S [--task I ...] --init-states A:B --operator pick --seed K --out PATH
  [--noise M] [--workers W] [--json]``: record the operator's runs (HDF5, ``skill_data``);
- ``train --data PATH [PATH ...] --out DIR [--steps N] [--seed K] [--json]``: TD3+BC on
  them; writes ``DIR/skills/<skill>.*`` and ``DIR/manifest.json``.
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from pathlib import Path

from osg_control.errors import UsageError
from osg_control.libero.suites import max_steps, parse_init_states, suite_names

SKILLS = ("pick",)
"""The operators' skills ``collect`` records (``recording.OPERATORS``)."""
DATA_SUFFIXES = (".h5", ".hdf5")
TRAIN_STEPS = 20_000
"""TD3+BC updates ``train`` runs by default."""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``collect`` and ``train``."""
    collect = subparsers.add_parser(
        "collect",
        help="record a LIBERO operator's runs with exploration noise (Algorithm 1)",
        description="Run the scripted-plan executor from the tasks' fixed initial states; "
        "while the operator runs, perturb its scripted commands with seeded Gaussian noise "
        "and record the lifted observation and action per step, rewarded when its effect "
        "is perceived.",
    )
    collect.add_argument("--suite", required=True, help=f"the suite: {', '.join(suite_names())}")
    collect.add_argument("--task", type=int, nargs="+", default=None, metavar="I",
                         help="task indices in the suite (default: all)")  # fmt: skip
    collect.add_argument("--init-states", required=True, metavar="A:B",
                         help="initial states A .. B-1 of each task")  # fmt: skip
    collect.add_argument("--operator", required=True, help=f"the skill: {', '.join(SKILLS)}")
    collect.add_argument("--seed", type=int, default=0, help="the noise's and scene's seed")
    collect.add_argument("--noise", type=float, default=None, metavar="M",
                         help="exploration noise std on the TCP target [m] (default 0.005; "
                         "the wrist yaw's scaled by the action bounds' ratio)")  # fmt: skip
    collect.add_argument("--out", type=Path, required=True, help="the HDF5 file to write")
    collect.add_argument("--workers", type=int, default=1)
    collect.add_argument("--json", action="store_true")
    collect.set_defaults(func=run_collect)
    train = subparsers.add_parser(
        "train",
        help="train a lifted LIBERO skill (TD3+BC) on collected data",
        description="TD3+BC on one skill's data files: one network for every object; "
        "writes DIR/skills/<skill>.safetensors + .json and DIR/manifest.json.",
    )
    train.add_argument("--data", type=Path, nargs="+", required=True, metavar="PATH")
    train.add_argument("--out", type=Path, required=True, metavar="DIR")
    train.add_argument("--steps", type=int, default=TRAIN_STEPS,
                       help=f"TD3+BC updates (default {TRAIN_STEPS})")  # fmt: skip
    train.add_argument("--seed", type=int, default=0)
    train.add_argument("--threads", type=int, default=1, help="torch's CPU threads (default 1)")
    train.add_argument("--json", action="store_true")
    train.set_defaults(func=run_train)


def _check_out(path: Path, suffixes: tuple[str, ...] | None) -> None:
    """Refuse an output inside the package or of the wrong kind (exit 2)."""
    from osg_control.errors import OutputError
    from osg_control.io_safety import refuse_package

    if suffixes is not None and path.suffix not in suffixes:
        raise UsageError(f"--out: {path} must end in {' or '.join(suffixes)}")
    try:
        refuse_package(path)
    except OutputError as err:
        raise UsageError(f"--out: {err}") from None


def run_collect(args: argparse.Namespace) -> int:
    """Record the operator's runs and write them (``recording``, ``skill_data``)."""
    budget = max_steps(args.suite)
    states = parse_init_states(args.init_states)
    if args.operator not in SKILLS:
        raise UsageError(
            f"--operator: no recorder for {args.operator!r}; known: {', '.join(SKILLS)}"
        )
    _check_out(args.out, DATA_SUFFIXES)
    from osg_control.io_safety import check_output_dir
    from osg_control.json_files import dump_json
    from osg_control.libero.recording import (
        NOISE_STD,
        CollectJob,
        collect_job,
        episodes_sha256,
        pick_skill,
    )
    from osg_control.libero.skill_data import write_skill_data
    from osg_control.libero.tasks import check_task_indices
    from osg_control.parallel import LocalExecutor

    tasks = check_task_indices(args.suite, args.task)
    check_output_dir(args.out.parent or Path("."), "output folder")
    noise = NOISE_STD if args.noise is None else args.noise
    jobs = [CollectJob(args.suite, t, tuple(states), args.operator, args.seed, noise, budget)
            for t in tasks]  # fmt: skip
    start = time.process_time()
    episodes = [e for done in LocalExecutor(args.workers).map(collect_job, jobs) for e in done]
    cpu_s = time.process_time() - start
    attrs = {"suite": args.suite, "operator": args.operator, "seed": args.seed,
             "noise_std": noise, "skill": pick_skill(noise).to_json(),
             "command": shlex.join(["osg", *sys.argv[1:]])}  # fmt: skip
    sha256 = write_skill_data(args.out, episodes, attrs)
    wins = sum(e.success for e in episodes)
    summary = {
        "out": str(args.out), "sha256": sha256, "episodes_sha256": episodes_sha256(episodes),
        "suite": args.suite, "tasks": list(tasks), "init_states": [states.start, states.stop],
        "operator": args.operator, "seed": args.seed, "noise_std": noise,
        "episodes": len(episodes), "steps": sum(len(e.actions) for e in episodes),
        "successes": wins, "success_rate": wins / len(episodes) if episodes else 0.0,
        "cpu_s": round(cpu_s, 1),
    }  # fmt: skip
    if args.json:
        print(dump_json(summary))
    else:
        print(
            f"wrote {args.out}: {len(episodes)} {args.operator} episodes, "
            f"{summary['steps']} steps, {wins} perceived successes (seed {args.seed})"
        )
    return 0


def run_train(args: argparse.Namespace) -> int:
    """Train the data's skill and write the skills folder (``training``)."""
    for path in args.data:
        if path.suffix not in DATA_SUFFIXES:
            raise UsageError(f"--data: {path} must end in {' or '.join(DATA_SUFFIXES)}")
    _check_out(args.out, None)
    from osg_control.io_safety import check_output_dir
    from osg_control.json_files import dump_json
    from osg_control.libero.skill_data import load_skill_data
    from osg_control.libero.training import train_skill, write_skills

    datasets = [load_skill_data(path) for path in args.data]
    check_output_dir(args.out)
    checkpoint, log = train_skill(datasets, args.steps, args.seed, threads=args.threads)
    command = shlex.join(["osg", *sys.argv[1:]])
    manifest = write_skills(args.out, checkpoint, datasets, command, log)
    summary = {"out": str(args.out), "manifest": str(manifest), "skill": checkpoint.skill.name,
               "steps": args.steps, "seed": args.seed, "dataset_sha256": checkpoint.dataset_sha256,
               "episodes": sum(d.num_episodes for d in datasets), **log}  # fmt: skip
    if args.json:
        print(dump_json(summary))
    else:
        print(f"wrote {args.out}: skill {checkpoint.skill.name}, {args.steps} updates "
              f"in {log['cpu_s']} s CPU")  # fmt: skip
    return 0
