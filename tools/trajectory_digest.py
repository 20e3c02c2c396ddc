"""A sha256 digest of a domain env's trajectories, to show a refactor changed nothing.

Random actions on several skills under the ``sim``, ``paper`` (2 cm TCP noise) and
``robot`` perceptions (every observation, percept state, perceived joints and world,
facts, applied action, true world, arm joints and joint-speed ratio), a joint reset after
each run, and a few episodes of scripted collection (Algorithm 1: every array of each
episode) are hashed byte for byte. The same code on the same machine gives the same digest
exactly when the physics, IK and sensors did the same arithmetic.

Usage:
    python tools/trajectory_digest.py [--domain kitchen] [--steps 60] [--episodes 2]
        [--ik-backend pinocchio]
"""

from __future__ import annotations

import argparse
import hashlib
import json
from typing import Any

import numpy as np

from osg_control.control.ik import IKConfig
from osg_control.data.collect import run_scripted_episode
from osg_control.domain.registry import get_domain
from osg_control.environment.arm_env import EnvConfig
from osg_control.perception.spec import perception_spec

PERCEPTIONS = (("sim", 0.0), ("paper", 0.02), ("robot", 0.0))
FIELDS = (
    "observations", "next_observations", "actions", "rewards", "terminations", "truncations",
    "world_states",
)  # fmt: skip


def _update(digest: Any, *values: Any) -> None:
    for value in values:
        if isinstance(value, np.ndarray):
            digest.update(np.ascontiguousarray(value, dtype=np.float64).tobytes())
        else:
            digest.update(repr(value).encode())


def env_digest(
    domain_name: str, skills: list[str], steps: int, seed: int, backend: str = "mink"
) -> str:
    """The digest of ``steps`` random steps per skill and perception, then a joint reset,
    with the IK's ``backend``."""
    domain = get_domain(domain_name)
    by_name = {s.name: s for s in domain.skills}
    digest = hashlib.sha256()
    for k, (perception, noise) in enumerate(PERCEPTIONS):
        for i, name in enumerate(skills):
            config = EnvConfig(
                perception=perception_spec(perception, noise), ik=IKConfig(backend=backend)
            )
            env = domain.make_env(skill=by_name[name], config=config)
            rng = np.random.default_rng([seed, k, i])
            obs, info = env.reset(seed=seed + 100 * k + i)
            _update(digest, obs, info["world"], env.percept().joints)
            for _ in range(steps):
                action = rng.uniform(-1.5, 1.5, 7) * env.action_space.high  # some clipped
                obs, reward, terminated, truncated, info = env.step(action)
                percept = info["percept"]
                _update(
                    digest, obs, reward, terminated, truncated, info["action_applied"],
                    info["world"], info["arm_q"], info["joint_speed_ratio"],
                    percept.state, percept.joints, percept.world, sorted(percept.facts),
                )  # fmt: skip
                if terminated or truncated:
                    obs, info = env.reset(seed=seed + 7 * k + i)
                    _update(digest, obs)
            _update(digest, env.joint_reset(), env.arm_q, env.percept().state)
            env.close()
    return digest.hexdigest()


def collect_digest(domain_name: str, skills: list[str], episodes: int, seed: int) -> str:
    """The digest of ``episodes`` scripted (Algorithm 1) episodes per skill."""
    domain = get_domain(domain_name)
    by_name = {s.name: s for s in domain.skills}
    digest = hashlib.sha256()
    for name in skills:
        for index in range(episodes):
            episode = run_scripted_episode(domain, by_name[name], seed, index)
            for field in FIELDS:
                _update(digest, np.asarray(getattr(episode, field), dtype=np.float64))
    return digest.hexdigest()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--domain", default="kitchen")
    parser.add_argument(
        "--skills", nargs="+", help="skills to step (default: six spread over the domain's)"
    )
    parser.add_argument("--steps", type=int, default=60, help="random steps per run")
    parser.add_argument("--episodes", type=int, default=2, help="scripted episodes per skill")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--ik-backend", default="mink", help="the env's IK backend")
    args = parser.parse_args()
    domain = get_domain(args.domain)
    names = args.skills or [s.name for s in domain.skills[:: max(1, len(domain.skills) // 6)]]
    result = {
        "skills": names,
        "env_steps": args.steps * len(names) * len(PERCEPTIONS),
        "ik_backend": args.ik_backend,
        "env": env_digest(args.domain, names, args.steps, args.seed, args.ik_backend),
        "collect": collect_digest(args.domain, names, args.episodes, args.seed),
    }
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
