"""Tune Algorithm 1's action noise or step budget per skill so that the scripted success
rate lies in the paper's 40-50 % band.

Usage: python tools/tune_scripts.py --domain NAME [--knob noise|steps] [--skill S ...]
       [--episodes N] [--seed S] [--workers W] [--low L] [--high H] [--rounds R] [--json]

For each skill, bisects one of Algorithm 1's parameters between ``--low`` and ``--high``,
starting from the skill's present value: ``--episodes`` episodes of the skill's own script
through the core's collector, success as the collector records it (the skill's beta).

- ``noise`` (default): sigma_2, the Gaussian noise on every motion component, on a log
  scale in millimetres (orientation noise scales with it, see ``osg_control.data.scripted``;
  default range 1-40 mm); more noise, lower rate.
- ``steps``: the per-waypoint step budget, an integer (default range 1-60); more steps,
  higher rate. Waypoints with their own budget keep it.

Stops when a rate lands in [0.40, 0.50] or after ``--rounds`` rounds; prints the chosen
value and its measured rate per skill, to be written into the domain's Algorithm 1
parameters. Episodes run in ``--workers`` processes; the result does not depend on their
number.
"""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np

from osg_control.data.collect import run_scripted_episode
from osg_control.domain.registry import get_domain
from osg_control.domain.spec import ScriptParams, SkillSpec
from osg_control.parallel import LocalExecutor

BAND = (0.40, 0.50)


@dataclass(frozen=True)
class Knob:
    """One of Algorithm 1's parameters, as the bisection sees it."""

    field: str
    rate_rises: bool
    """Whether the success rate rises with the value."""
    integer: bool
    default_range: tuple[float, float]

    def midpoint(self, low: float, high: float) -> float:
        """The next trial between ``low`` and ``high``."""
        if self.integer:
            return float(round((low + high) / 2))
        return math.exp((math.log(low) + math.log(high)) / 2)

    def value(self, script: ScriptParams) -> float:
        """The skill's present value."""
        return float(getattr(script, self.field))

    def applied(self, skill: SkillSpec, value: float) -> SkillSpec:
        """``skill`` with the value set."""
        typed = int(value) if self.integer else value
        return replace(skill, script=replace(skill.script, **{self.field: typed}))


KNOBS = {
    "noise": Knob("noise_std", rate_rises=False, integer=False, default_range=(0.001, 0.04)),
    "steps": Knob("steps_per_waypoint", rate_rises=True, integer=True, default_range=(1, 60)),
}


def _success(domain: str, skill: Any, seed: int, index: int) -> bool:
    return run_scripted_episode(get_domain(domain), skill, seed, index).success


def rate(domain: str, skill: SkillSpec, episodes: int, seed: int, pool: Any) -> float:
    """The scripted success rate of ``skill`` as given."""
    outcomes = pool.map(partial(_success, domain, skill, seed), list(range(episodes)))
    return float(np.mean(list(outcomes)))


def tune(
    domain: str,
    name: str,
    knob: Knob,
    episodes: int,
    seed: int,
    low: float,
    high: float,
    rounds: int,
    pool: Any,
) -> dict[str, Any]:
    """Bisect one knob of one skill (see module doc)."""
    skill = get_domain(domain).skill(name)
    trials: list[tuple[float, float]] = []
    value = knob.value(skill.script)
    for _ in range(rounds):
        measured = rate(domain, knob.applied(skill, value), episodes, seed, pool)
        trials.append((round(value, 5), measured))
        if BAND[0] <= measured <= BAND[1]:
            break
        if (measured > BAND[1]) != knob.rate_rises:
            low = value + 1 if knob.integer else value
        else:
            high = value - 1 if knob.integer else value
        if low > high:
            break
        value = knob.midpoint(low, high)
    best = min(trials, key=lambda t: abs(t[1] - sum(BAND) / 2))
    return {"skill": name, knob.field: best[0], "rate": best[1], "trials": trials}


def main() -> None:
    """Parse the arguments, tune each skill, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--domain", required=True)
    parser.add_argument("--skill", nargs="*", default=None, help="default: every skill")
    parser.add_argument("--episodes", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--knob", choices=sorted(KNOBS), default="noise")
    parser.add_argument("--low", type=float, help="smallest value (noise in mm, or steps)")
    parser.add_argument("--high", type=float, help="largest value (noise in mm, or steps)")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    domain = get_domain(args.domain)
    knob = KNOBS[args.knob]
    unit = 1000.0 if args.knob == "noise" else 1.0  # noise is given and printed in mm
    low = knob.default_range[0] if args.low is None else args.low / unit
    high = knob.default_range[1] if args.high is None else args.high / unit
    names = args.skill or [s.name for s in domain.skills]
    results = []
    pool = LocalExecutor(args.workers)
    for name in names:
        result = tune(
            domain.name,
            name,
            knob,
            args.episodes,
            args.seed,
            low,
            high,
            args.rounds,
            pool,
        )
        results.append(result)
        if not args.json:
            print(
                f"{name:30s} {knob.field} {result[knob.field] * unit:6.2f}  rate "
                f"{result['rate']:.3f}  trials {result['trials']}",
                flush=True,
            )
    if args.json:
        print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
