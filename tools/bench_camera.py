"""Measure the ``camera`` perception: its cube estimate against the truth, and its cost.

Usage: python tools/bench_camera.py [--placements N] [--steps N] [--seed S]
[--start NODE --radius R --angle A] [--json] (needs MUJOCO_GL=egl or osmesa).

1. Accuracy: ``--placements`` cubes placed uniformly in the cube's placement region (seeded),
   each read at the reset (a decision point: a render): the error of the estimated centre
   against the simulator's, and how many placements no camera saw. The arm starts at home,
   or at ``--start``'s node (anchored nodes moved with the cube) within ``--radius`` [m]
   and ``--angle`` [rad], where the hand may hide the cube.
2. Cost: wall time per render (every camera, RGB + depth where the mask sees something, and
   the estimate), and per control step of ``--steps`` still steps under ``camera`` and
   ``robot`` (the slowdown of the env alone; an episode also runs the policies and the
   executor, see ``osg evaluate tasks``).
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import numpy as np

from osg_control.environment.arm_env import EnvConfig
from osg_control.kitchen.env import KitchenEnv
from osg_control.kitchen.skills import CUBE
from osg_control.perception.spec import perception_spec

CUBE_POSITION = slice(2, 5)
"""The cube's centre in the kitchen's world vector."""


def accuracy(
    placements: int, seed: int, start: str = "home", radius: float = 0.0, angle: float = 0.0
) -> dict[str, Any]:
    """Estimation error [mm] over random placements (``CUBE``'s region), the arm started
    at ``start`` within ``radius`` and ``angle``."""
    env = KitchenEnv(config=EnvConfig(perception=perception_spec("camera")))
    rng = np.random.default_rng(seed)
    errors, unseen = [], 0
    for episode in range(placements):
        x, y = rng.uniform(CUBE.region_low, CUBE.region_high)
        world = {"cube_pos": [x, y, CUBE.rest_z]}
        options = {"node": start, "radius": radius, "angle": angle, "world": world}
        env.reset(seed=episode, options=options)
        estimate = env.percept().world[CUBE_POSITION]
        if not np.isfinite(estimate).all():
            unseen += 1
            continue
        errors.append(float(np.linalg.norm(estimate - env.world_state()[CUBE_POSITION])))
    assert env.cameras is not None
    mm = np.array(errors) * 1000
    result = {
        "placements": placements,
        "start": start,
        "radius": radius,
        "unseen": unseen,
        "over_10_mm": int((mm > 10).sum()),
        "mean_mm": round(float(mm.mean()), 3),
        "median_mm": round(float(np.median(mm)), 3),
        "p95_mm": round(float(np.percentile(mm, 95)), 3),
        "max_mm": round(float(mm.max()), 3),
        "render_ms": round(1000 * env.cameras.seconds / env.cameras.renders, 2),
    }
    env.close()
    return result


def step_cost(steps: int) -> dict[str, float]:
    """Wall time per still control step [ms] under ``camera`` and ``robot``."""
    cost = {}
    for name in ("camera", "robot"):
        env = KitchenEnv(config=EnvConfig(perception=perception_spec(name), max_steps=None))
        env.reset(seed=0)
        started = time.perf_counter()
        for _ in range(steps):
            env.step(np.zeros(7))
        cost[f"{name}_step_ms"] = round(1000 * (time.perf_counter() - started) / steps, 3)
        env.close()
    cost["env_slowdown"] = round(cost["camera_step_ms"] / cost["robot_step_ms"], 2)
    return cost


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--placements", type=int, default=200)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--start", default="home", help="the arm's start node")
    parser.add_argument("--radius", type=float, default=0.0, help="start radius [m]")
    parser.add_argument("--angle", type=float, default=0.0, help="start angle per axis [rad]")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    result = {"spec": perception_spec("camera").to_dict()}
    result.update(accuracy(args.placements, args.seed, args.start, args.radius, args.angle))
    result.update(step_cost(args.steps))
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for key, value in result.items():
            print(f"{key}: {value}")


if __name__ == "__main__":
    main()
