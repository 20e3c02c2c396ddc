"""A sha256 digest of a domain env's trajectories, to show a refactor changed nothing.

Random actions on several skills under the ``sim``, ``paper`` (2 cm TCP noise) and
``robot`` perceptions (every observation, percept state, perceived joints and world,
facts, applied action, true world, arm joints and joint-speed ratio), a joint reset after
each run, and a few episodes of scripted collection (Algorithm 1: every array of each
episode) are hashed byte for byte. The same code on the same machine gives the same digest
exactly when the physics, IK and sensors did the same arithmetic. ``--columns legacy``
hashes the world vectors without the fields appended since the digests of record
(``APPENDED_FIELDS``): a change that only adds those gives the old digests.

Usage:
    python tools/trajectory_digest.py [--domain kitchen] [--steps 60] [--episodes 2]
        [--ik-backend pinocchio] [--columns legacy]
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
APPENDED_FIELDS = ("valve_x", "valve_y")
"""World fields appended after the digests of record (the kitchen's valve place)."""
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


def kept_columns(domain_name: str, legacy: bool) -> np.ndarray | slice:
    """The world vector's columns hashed: all, or (``legacy``) all but ``APPENDED_FIELDS``."""
    fields = get_domain(domain_name).world_fields
    if not legacy:
        return slice(None)
    return np.array([i for i, name in enumerate(fields) if name not in APPENDED_FIELDS])


def env_digest(
    domain_name: str,
    skills: list[str],
    steps: int,
    seed: int,
    backend: str = "mink",
    legacy: bool = False,
) -> str:
    """The digest of ``steps`` random steps per skill and perception, then a joint reset,
    with the IK's ``backend`` (``legacy``: ``kept_columns``)."""
    domain = get_domain(domain_name)
    by_name = {s.name: s for s in domain.skills}
    cols = kept_columns(domain_name, legacy)
    digest = hashlib.sha256()
    for k, (perception, noise) in enumerate(PERCEPTIONS):
        for i, name in enumerate(skills):
            config = EnvConfig(
                perception=perception_spec(perception, noise), ik=IKConfig(backend=backend)
            )
            env = domain.make_env(skill=by_name[name], config=config)
            rng = np.random.default_rng([seed, k, i])
            obs, info = env.reset(seed=seed + 100 * k + i)
            _update(digest, obs, info["world"][cols], env.percept().joints)
            for _ in range(steps):
                action = rng.uniform(-1.5, 1.5, 7) * env.action_space.high  # some clipped
                obs, reward, terminated, truncated, info = env.step(action)
                percept = info["percept"]
                _update(
                    digest, obs, reward, terminated, truncated, info["action_applied"],
                    info["world"][cols], info["arm_q"], info["joint_speed_ratio"],
                    percept.state, percept.joints, percept.world[cols], sorted(percept.facts),
                )  # fmt: skip
                if terminated or truncated:
                    obs, info = env.reset(seed=seed + 7 * k + i)
                    _update(digest, obs)
            _update(digest, env.joint_reset(), env.arm_q, env.percept().state)
            env.close()
    return digest.hexdigest()


def collect_digest(
    domain_name: str, skills: list[str], episodes: int, seed: int, legacy: bool = False
) -> str:
    """The digest of ``episodes`` scripted (Algorithm 1) episodes per skill (``legacy``:
    ``kept_columns`` of the world states)."""
    domain = get_domain(domain_name)
    cols = kept_columns(domain_name, legacy)
    by_name = {s.name: s for s in domain.skills}
    digest = hashlib.sha256()
    for name in skills:
        for index in range(episodes):
            episode = run_scripted_episode(domain, by_name[name], seed, index)
            for field in FIELDS:
                values = np.asarray(getattr(episode, field), dtype=np.float64)
                _update(digest, values[:, cols] if field == "world_states" else values)
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
    parser.add_argument(
        "--columns",
        choices=("all", "legacy"),
        default="all",
        help="world columns hashed: all, or legacy (without APPENDED_FIELDS)",
    )
    args = parser.parse_args()
    legacy = args.columns == "legacy"
    domain = get_domain(args.domain)
    names = args.skills or [s.name for s in domain.skills[:: max(1, len(domain.skills) // 6)]]
    result = {
        "skills": names,
        "env_steps": args.steps * len(names) * len(PERCEPTIONS),
        "ik_backend": args.ik_backend,
        "columns": args.columns,
        "env": env_digest(args.domain, names, args.steps, args.seed, args.ik_backend, legacy),
        "collect": collect_digest(args.domain, names, args.episodes, args.seed, legacy),
    }
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
