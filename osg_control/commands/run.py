"""``osg run`` (execute a task), ``osg eval-skills`` (Table I), ``osg evaluate tasks`` (IV/V)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

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
from osg_control.domain.frames import offsets_of, sample_placements
from osg_control.errors import UsageError
from osg_control.evaluation.skill_table import format_skill_table, skill_table
from osg_control.execution.defaults import defaults_root, describe_models, models_in_use
from osg_control.execution.executor import load_executor, task_env_config
from osg_control.execution.goals import parse_goal
from osg_control.io_safety import atomic_write, check_output_dir
from osg_control.json_files import dump_json
from osg_control.parallel import open_executor
from osg_control.perception.spec import perception_spec

if TYPE_CHECKING:
    from osg_control.execution.recording import RunRecorder


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``run``, ``eval-skills`` and ``evaluate`` to the ``osg`` parser."""
    run = subparsers.add_parser("run", help="execute a task: classify, plan, run skills")
    run.add_argument("--goal", required=True, help='world facts, e.g. "door-open cube-in-cabinet"')
    run.add_argument(
        "--start",
        default="random",
        help="'random' (one of the domain's start regions, e.g. 15 cm / 0.2 rad) or a node name",
    )
    run.add_argument(
        "--episodes", type=int, default=1, help="episodes to run, each from a new start (default 1)"
    )
    run.add_argument(
        "--noise", type=float, default=None, help="the paper protocol's TCP noise sigma [m]"
    )
    add_perception_arguments(run)
    add_randomize_argument(run)
    run.add_argument(
        "--seed", type=int, default=0, help="seeds the starts and the noise (default 0)"
    )
    run.add_argument(
        "--facts",
        default=None,
        help="world facts at the start, space-separated (default: the domain's start world)",
    )
    run.add_argument(
        "--max-replans",
        type=int,
        default=2,
        help="times a failed plan is re-planned per episode (0: the paper's executor; default 2)",
    )
    run.add_argument("--models", type=Path, default=None, help="defaults directory to use")
    run.add_argument("--video", type=Path, default=None, help="write an MP4 of the first episode")
    run.add_argument(
        "--video-camera",
        default=None,
        metavar="NAME",
        help="the scene camera the video films from (default: its overview camera; e.g. the "
        "kitchen's counter_cam to watch what the camera perception sees)",
    )
    run.add_argument(
        "--rerun",
        type=Path,
        default=None,
        metavar="FILE.rrd",
        help="record every episode for the rerun viewer (`rerun FILE.rrd`): TCP path, target "
        "nodes, joints, gripper, skills, plans, replans, failures (needs the [viz] extra)",
    )
    add_filter_argument(run)
    run.add_argument(
        "--json",
        action="store_true",
        help="print one JSON object (models, perception, episodes, success rate)",
    )
    run.set_defaults(func=run_task)

    skills = subparsers.add_parser("eval-skills", help="Table I: learned skills under noise")
    skills.add_argument("--episodes", type=int, default=200)
    skills.add_argument(
        "--noise",
        type=float,
        nargs="+",
        default=None,
        help="the paper protocol's TCP noise of each column [m] (default 0 0.01 0.02; 0 under "
        "the other perceptions)",
    )
    add_perception_arguments(skills)
    add_randomize_argument(skills)
    skills.add_argument("--seed", type=int, default=0)
    skills.add_argument("--workers", type=int, default=2)
    add_backend_arguments(skills)
    skills.add_argument("--skill", nargs="*", default=None, help="default: all")
    skills.add_argument(
        "--models",
        type=Path,
        default=None,
        help="skill checkpoint directory (default: the domain's shipped skills)",
    )
    add_filter_argument(skills)
    skills.add_argument("--json", action="store_true")
    skills.set_defaults(func=run_eval_skills)


def _start_options(domain: Domain, start: str, rng: np.random.Generator) -> dict[str, Any]:
    if start == "random":
        region = domain.start_regions[int(rng.integers(len(domain.start_regions)))]
        return {"position": region.position, "radius": region.radius, "angle": region.angle}
    if start not in domain.nodes:
        raise UsageError(
            f"--start: unknown start {start!r}; use 'random' or one of {list(domain.nodes)}"
        )
    return {"node": start, "radius": 0.0, "angle": 0.0}


def run_task(args: argparse.Namespace) -> int:
    """Run ``--episodes`` executions of the goal and report each (exit 1 if any failed)."""
    domain = domain_of(args)
    perception = perception_of(args, domain)
    try:
        goal = parse_goal(args.goal, domain)
    except ValueError as err:
        raise UsageError(f"--goal: {err}") from None
    facts = domain.start_world if args.facts is None else tuple(args.facts.split())
    if args.video:
        check_output_dir(args.video.parent, "video folder")
    recorder = _recorder(args.rerun, domain)
    executor = load_executor(
        domain, args.models, max_replans=args.max_replans, filter_gain=args.filter
    )
    models = models_in_use(domain, args.models)
    if not args.json:
        print(describe_models(models))
    env = domain.make_env(
        config=task_env_config(perception),
        render_mode="rgb_array" if args.video else None,
    )
    if args.video_camera is not None:
        _film_from(env, args.video_camera)
    rng = np.random.default_rng(args.seed)
    results = []
    frames: list[Any] = []
    for episode in range(args.episodes):
        options = _start_options(domain, args.start, rng)
        options["facts"] = facts
        if args.randomize_objects:
            world = env.placement_world(sample_placements(domain, rng), None)
            if world:
                options["world"] = world
        obs, _ = env.reset(seed=int(rng.integers(2**31)), options=options)
        video = bool(args.video) and episode == 0
        executor.on_step = _step_hook(video, frames, recorder)
        if recorder is not None:
            recorder.begin_episode(env)
            executor.on_event = recorder.on_event
        result = executor.execute(goal.atoms(), env, obs)
        truth = offsets_of(domain.objects, domain.world_fields, env.world_state())
        scored = goal.holds(domain, env.facts(), env.true_state(), truth)  # the truth scores
        results.append({**result.to_dict(), "scored_success": scored})
        if not args.json:
            status = "success" if result.success else f"FAILED ({result.failure})"
            entry = f"entry {result.entry_skill}, " if result.entry_skill else ""
            print(
                f"episode {episode}: {status}; {entry}plan {' -> '.join(result.plan) or '(empty)'}"
                f"; replans {result.replans}; {result.timings['total_s']:.2f} s"
            )
    if args.video and frames:
        _write_video(args.video, frames, domain.control_hz)
    if recorder is not None:
        path = recorder.close()
        if not args.json:
            print(f"rerun recording written to {path} (view it: rerun {path})")
    successes = sum(r["scored_success"] for r in results)
    if args.json:
        payload = {
            "models": models,
            "perception": perception.to_dict(),
            **(
                {"cameras": camera_setups(domain, perception)}
                if perception.name == "camera"
                else {}
            ),
            "episodes": results,
            "success_rate": successes / len(results),
        }
        if perception.name == "camera":
            payload["cameras"] = camera_setups(domain, perception)
        print(dump_json(payload))
    else:
        print(f"success rate {successes}/{len(results)}")
    return 0 if successes == len(results) else 1


def _film_from(env: Any, camera: str) -> None:
    """Point ``render`` (the video) at a scene camera.

    Raises:
        UsageError: an env that films from its own view (an outside env's ``render``), or
            a camera the scene lacks (its cameras listed); exit 2, no episode run.
    """
    if not isinstance(getattr(env, "camera", None), str):
        raise UsageError(
            f"--video-camera: {type(env).__name__} renders its own view; it takes no camera"
        )
    cameras = [env.model.camera(i).name for i in range(env.model.ncam)]
    if camera not in cameras:
        raise UsageError(
            f"--video-camera: the scene has no camera {camera!r}; its cameras: {cameras}"
        )
    env.camera = camera


def _recorder(path: Path | None, domain: Domain) -> RunRecorder | None:
    """The ``--rerun`` recorder (None without the flag).

    Raises:
        UsageError: not an ``.rrd`` file name, or rerun-sdk missing (exit 2, nothing run).
    """
    if path is None:
        return None
    if path.suffix != ".rrd":
        raise UsageError(f"--rerun: {path} must end in .rrd")
    from osg_control.execution.recording import RunRecorder

    check_output_dir(path.parent, "recording folder")
    return RunRecorder(path, domain)


def _step_hook(
    video: bool, frames: list[Any], recorder: RunRecorder | None
) -> Callable[[Any], None] | None:
    """The executor's ``on_step``: render a video frame, record the percept (or None)."""
    if not video and recorder is None:
        return None

    def hook(env: Any) -> None:
        frame = env.render() if video else None
        if video:
            frames.append(frame)
        if recorder is not None:
            recorder.on_step(env, frame)

    return hook


def _write_video(path: Path, frames: list[Any], fps: float) -> None:
    import imageio.v2 as imageio

    atomic_write(path, lambda tmp: imageio.mimwrite(tmp, frames, fps=fps))
    print(f"video written to {path}")


def run_eval_skills(args: argparse.Namespace) -> int:
    """Print Table I."""
    domain = domain_of(args)
    perception = perception_of(args, domain)
    noise = args.noise or ([0.0, 0.01, 0.02] if perception.name == "paper" else [0.0])
    for level in noise:
        perception_spec(perception.name, level, args.object_noise)  # refuse a bad level
    models = args.models or defaults_root(domain) / "skills"
    with open_executor(args.backend, args.workers, args.address) as executor:
        table = skill_table(
            domain,
            models,
            noise,
            args.episodes,
            args.seed,
            args.workers,
            args.skill,
            filter_gain=args.filter,
            executor=executor,
            progress=not args.json,
            perception=perception,
            randomize=args.randomize_objects,
        )
    table["models"] = {"skills": str(models)}
    print(dump_json(table) if args.json else format_skill_table(table))
    if not args.json:
        print(f"models: {args.models}")
    return 0
