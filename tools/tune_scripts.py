"""Tune Algorithm 1's action noise per skill so that the scripted success rate lies in the
paper's 40-50 % band.

Usage: python tools/tune_scripts.py --domain NAME [--skill S ...] [--episodes N]
       [--seed S] [--workers W] [--low MM] [--high MM] [--rounds R] [--json]

For each skill, bisects sigma_2 (the Gaussian noise on every motion component, in metres;
orientation noise scales with it, see ``osg_control.data.scripted``) on a log scale between
``--low`` and ``--high`` millimetres: ``--episodes`` episodes of the skill's own script
(its threshold and step budgets kept) through the core's collector, success as the
collector records it (the skill's beta). Stops when a rate lands in [0.40, 0.50] or after
``--rounds`` rounds; prints the chosen sigma_2 and its measured rate per skill, to be
written into the domain's Algorithm 1 parameters. Episodes run in ``--workers`` processes;
the result does not depend on their number.
"""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import replace
from functools import partial
from typing import Any

import numpy as np

from osg_control.data.collect import run_scripted_episode
from osg_control.domain.registry import get_domain
from osg_control.parallel import LocalExecutor

BAND = (0.40, 0.50)


def _success(domain: str, skill: Any, seed: int, index: int) -> bool:
    return run_scripted_episode(get_domain(domain), skill, seed, index).success


def rate(domain: str, skill: Any, noise: float, episodes: int, seed: int, pool: Any) -> float:
    """The scripted success rate of ``skill`` with action noise ``noise`` [m]."""
    noisy = replace(skill, script=replace(skill.script, noise_std=noise))
    outcomes = pool.map(partial(_success, domain, noisy, seed), list(range(episodes)))
    return float(np.mean(list(outcomes)))


def tune(
    domain: str,
    name: str,
    episodes: int,
    seed: int,
    low: float,
    high: float,
    rounds: int,
    pool: Any,
) -> dict[str, Any]:
    """Bisect the noise of one skill (see module doc)."""
    skill = get_domain(domain).skill(name)
    trials = []
    lo, hi = math.log(low), math.log(high)
    noise = skill.script.noise_std
    for _ in range(rounds):
        measured = rate(domain, skill, noise, episodes, seed, pool)
        trials.append((round(noise, 5), measured))
        if BAND[0] <= measured <= BAND[1]:
            break
        if measured > BAND[1]:
            lo = math.log(noise)
        else:
            hi = math.log(noise)
        noise = math.exp((lo + hi) / 2)
    best = min(trials, key=lambda t: abs(t[1] - sum(BAND) / 2))
    return {"skill": name, "noise_std": best[0], "rate": best[1], "trials": trials}


def main() -> None:
    """Parse the arguments, tune each skill, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--domain", required=True)
    parser.add_argument("--skill", nargs="*", default=None, help="default: every skill")
    parser.add_argument("--episodes", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--low", type=float, default=1.0, help="smallest sigma_2 [mm]")
    parser.add_argument("--high", type=float, default=40.0, help="largest sigma_2 [mm]")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    domain = get_domain(args.domain)
    names = args.skill or [s.name for s in domain.skills]
    results = []
    pool = LocalExecutor(args.workers)
    for name in names:
        result = tune(
            domain.name,
            name,
            args.episodes,
            args.seed,
            args.low / 1000,
            args.high / 1000,
            args.rounds,
            pool,
        )
        results.append(result)
        if not args.json:
            print(
                f"{name:30s} noise_std {result['noise_std'] * 1000:6.2f} mm  rate "
                f"{result['rate']:.3f}  trials {result['trials']}",
                flush=True,
            )
    if args.json:
        print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
