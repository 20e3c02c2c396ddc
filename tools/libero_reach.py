"""Measure our IK driving LIBERO's Panda through robosuite's JOINT_POSITION controller: a
scripted reach to 10 cm above an object, its pose read from the env's observation.

Usage: python tools/libero_reach.py [--suite S] [--task I] [--object NAME]
       [--init-states A:B] [--steps N] [--json]
Per initial state: the TCP's distance to the target at the start, the first step it is
within 1 cm and 2 mm, its final error; over all steps the IK's CPU time per step and the
joint tracking error (the observed joints one step later against the joints the IK
commanded). Needs the libero extra. Deterministic: no randomness.
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import numpy as np

from osg_control.libero.drive import JOINTS_OBS, TCP_OBS, JointTargetDriver
from osg_control.libero.env import JOINT_DELTA_LIMIT, LiberoEnv
from osg_control.libero.robot import mounted_panda
from osg_control.libero.suites import parse_init_states

ABOVE = np.array([0.0, 0.0, 0.10])


def first_within(errors: list[float], tolerance: float) -> int | None:
    """The first step whose error is below ``tolerance`` (None: never)."""
    return next((k + 1 for k, e in enumerate(errors) if e < tolerance), None)


def reach(env: LiberoEnv, state: int, obj: str, steps: int) -> dict[str, Any]:
    """One reach from initial state ``state``."""
    obs = env.reset(state)
    driver = JointTargetDriver(mounted_panda(env.sim))
    _, rotation = driver.tcp_pose(obs[JOINTS_OBS])
    target = obs[f"{obj}_pos"] + ABOVE
    start = float(np.linalg.norm(obs[TCP_OBS] - target))
    errors, ik_s, tracking = [], [], []
    for _ in range(steps):
        begin = time.process_time()
        action = driver.action(obs[JOINTS_OBS], target, rotation)
        ik_s.append(time.process_time() - begin)
        commanded = obs["robot0_joint_pos"] + action[:7] * JOINT_DELTA_LIMIT
        obs = env.step(action)
        tracking.append(float(np.abs(obs["robot0_joint_pos"] - commanded).max()))
        errors.append(float(np.linalg.norm(obs[TCP_OBS] - target)))
    return {
        "init_state": state,
        "start_distance_m": start,
        "steps_to_1cm": first_within(errors, 0.01),
        "steps_to_2mm": first_within(errors, 0.002),
        "final_error_m": errors[-1],
        "ik_ms_mean": 1e3 * float(np.mean(ik_s)),
        "tracking_rad_median": float(np.median(tracking)),
        "tracking_rad_max": float(np.max(tracking)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--suite", default="libero_10")
    parser.add_argument("--task", type=int, default=0)
    parser.add_argument("--object", default="alphabet_soup_1")
    parser.add_argument("--init-states", default="0:5")
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    env = LiberoEnv(args.suite, args.task)
    try:
        rows = [reach(env, s, args.object, args.steps) for s in parse_init_states(args.init_states)]
    finally:
        env.close()
    if args.json:
        print(json.dumps({"suite": args.suite, "task": args.task, "reaches": rows}, indent=2))
        return
    for row in rows:
        print(
            f"state {row['init_state']}: from {100 * row['start_distance_m']:.1f} cm, within 1 cm "
            f"at step {row['steps_to_1cm']}, 2 mm at {row['steps_to_2mm']}, final "
            f"{1000 * row['final_error_m']:.2f} mm; IK {row['ik_ms_mean']:.2f} ms/step; joint "
            f"tracking median {row['tracking_rad_median']:.3f} "
            f"max {row['tracking_rad_max']:.3f} rad"
        )


if __name__ == "__main__":
    main()
