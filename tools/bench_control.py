"""Benchmark the control stack: IK solve time per backend and solver, env step rate, overhead.

Prints, in one run:

- microseconds per ``DiffIKController.solve_velocity`` call (median and 90th percentile of
  ``--solves`` solves after ``--warmup`` untimed ones) for mink-daqp, mink-osqp,
  pinocchio-daqp and pinocchio-osqp, on varied targets within about 1 cm and 0.05 rad of
  the TCP pose at configurations around home;
- ``KitchenEnv.step`` calls per second with small random actions;
- the env step's overhead over its physics: each env step is followed by a timed block of
  ``n_substeps`` substeps in one ``mujoco.mj_step`` call (the physics' own ceiling) on the
  same model and data, and
  ``overhead = (median env step - median physics) / median physics`` (the IK, action
  checks, observation and world-state readout).

Timings are medians because the machine may be shared; the load average is printed with
them. Usage::

    python tools/bench_control.py            # human-readable
    python tools/bench_control.py --json     # one JSON object
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import time
import warnings
from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np

from osg_control.control.ik import DiffIKController, IKConfig
from osg_control.control.rotations import rotation_step
from osg_control.kitchen.env import KitchenEnv
from osg_control.robots.panda import PANDA

COMBINATIONS: tuple[tuple[str, str], ...] = (
    ("mink", "daqp"),
    ("mink", "osqp"),
    ("pinocchio", "daqp"),
    ("pinocchio", "osqp"),
)
IK_TARGET_US = 60.0
"""Target: mink-daqp median solve time [us]."""
OVERHEAD_TARGET = 0.25
"""Target: env-step overhead as a fraction of its physics time."""


def ik_problems(
    controller: DiffIKController, count: int, rng: np.random.Generator
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """``count`` (q, target position, target rotation) triples near the TCP pose.

    Configurations are home plus 0.2 rad Gaussian noise (within the joint limits); each
    target is the TCP pose there moved by up to 1 cm and rotated by about 0.03 rad per axis.
    """
    lower, upper = controller.backend.lower + 0.05, controller.backend.upper - 0.05
    problems = []
    for _ in range(count):
        q = np.clip(np.array(PANDA.home_q) + rng.normal(0.0, 0.2, 7), lower, upper)
        pos, rot = controller.tcp_pose(q)
        offset = rng.uniform(-0.01, 0.01, 3)
        problems.append((q, pos + offset, rotation_step(rot, rng.normal(0.0, 0.03, 3))))
    return problems


def median_and_p90(samples_ns: list[int]) -> tuple[float, float]:
    """Median and 90th percentile of nanosecond samples, in microseconds."""
    values = np.asarray(samples_ns, dtype=float) / 1e3
    return float(np.median(values)), float(np.percentile(values, 90))


def time_calls(call: Callable[[], Any], count: int) -> list[int]:
    """Nanoseconds of ``count`` calls of ``call``, with the garbage collector paused."""
    samples = []
    gc.disable()
    try:
        for _ in range(count):
            start = time.perf_counter_ns()
            call()
            samples.append(time.perf_counter_ns() - start)
    finally:
        gc.enable()
    return samples


def bench_ik(solves: int, warmup: int, seed: int) -> dict[str, dict[str, float]]:
    """Median and p90 microseconds per solve for every backend/solver combination."""
    results = {}
    for backend, solver in COMBINATIONS:
        controller = DiffIKController(PANDA, IKConfig(backend=backend, solver=solver))
        problems = ik_problems(controller, solves + warmup, np.random.default_rng(seed))
        for q, pos, rot in problems[:warmup]:
            controller.solve_velocity(q, pos, rot)
        queue = iter(problems[warmup:])

        def solve_next(ik: DiffIKController = controller, todo: Any = queue) -> None:
            ik.solve_velocity(*next(todo))

        median, p90 = median_and_p90(time_calls(solve_next, solves))
        results[f"{backend}-{solver}"] = {"median_us": median, "p90_us": p90}
    return results


def bench_env(steps: int, warmup: int, seed: int) -> dict[str, float]:
    """Env steps per second and the overhead of an env step over its raw physics."""
    env = KitchenEnv()
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    actions = rng.uniform(-0.5, 0.5, (steps + warmup, 7)) * env.action_bounds
    actions[:, 6] = 0.0  # gripper: hold
    model, data = env.model, env.data
    env_ns: list[int] = []
    physics_ns: list[int] = []
    gc.disable()
    try:
        for index, action in enumerate(actions):
            start = time.perf_counter_ns()
            _, _, terminated, truncated, _ = env.step(action)
            middle = time.perf_counter_ns()
            mujoco.mj_step(model, data, env.n_substeps)
            end = time.perf_counter_ns()
            if index >= warmup:
                env_ns.append(middle - start)
                physics_ns.append(end - middle)
            if terminated or truncated:
                env.reset(seed=seed + index)
    finally:
        gc.enable()
    env_median, env_p90 = median_and_p90(env_ns)
    physics_median, _ = median_and_p90(physics_ns)
    return {
        "env_step_median_us": env_median,
        "env_step_p90_us": env_p90,
        "env_steps_per_s": 1e6 * len(env_ns) / (sum(env_ns) / 1e3),
        "physics_median_us": physics_median,
        "n_substeps": float(env.n_substeps),
        "overhead": (env_median - physics_median) / physics_median,
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run the benchmark and print the figures (``--json``: one JSON object)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--solves", type=int, default=2000, help="timed IK solves per pair")
    parser.add_argument("--warmup", type=int, default=200, help="untimed solves/steps first")
    parser.add_argument("--env-steps", type=int, default=500, help="timed env steps")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # MuJoCo's spec-attach notice at model build
        ik = bench_ik(args.solves, args.warmup, args.seed)
        env = bench_env(args.env_steps, args.warmup // 4, args.seed)
    load = os.getloadavg()
    report: dict[str, Any] = {
        "ik": ik,
        "env": env,
        "machine": {"cpus": os.cpu_count(), "load_avg_1_5_15": list(load)},
        "targets": {
            "mink_daqp_median_le_60us": ik["mink-daqp"]["median_us"] <= IK_TARGET_US,
            "pinocchio_daqp_le_mink_daqp": (
                ik["pinocchio-daqp"]["median_us"] <= ik["mink-daqp"]["median_us"]
            ),
            "overhead_le_25pct": env["overhead"] <= OVERHEAD_TARGET,
        },
    }
    if args.json:
        print(json.dumps(report, indent=2))
        return report
    print(f"IK solve_velocity, {args.solves} solves each after {args.warmup} warm-up [us]:")
    for name, figures in ik.items():
        print(f"  {name:15s} median {figures['median_us']:8.1f}   p90 {figures['p90_us']:8.1f}")
    print(
        f"KitchenEnv.step: {env['env_steps_per_s']:.0f} steps/s "
        f"(median {env['env_step_median_us']:.0f} us, p90 {env['env_step_p90_us']:.0f} us)"
    )
    print(
        f"physics alone ({env['n_substeps']:.0f} substeps, one mj_step call): median "
        f"{env['physics_median_us']:.0f} us"
    )
    print(
        f"IK + observation overhead = (env step - physics)/physics = {100 * env['overhead']:.1f} %"
    )
    print(
        f"machine: {os.cpu_count()} CPUs, load average "
        f"{load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f} (1 / 5 / 15 min)"
    )
    for name, met in report["targets"].items():
        print(f"target {name}: {'met' if met else 'NOT met'}")
    return report


if __name__ == "__main__":
    main()
