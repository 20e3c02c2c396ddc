"""Write a learned LIBERO skill's measured success rate into its skills folder's manifest.

Usage: python tools/libero_skill_rate.py MANIFEST BENCH.json [BENCH.json ...] --skill pick
       --command "the benchmark command(s) run"

Reads ``osg --domain libero evaluate benchmark --policy skills --json`` outputs, adds up
the runs and perceived successes of the skill's operators (the summary's ``operators``,
from the episodes' traces), and sets the manifest's ``success_rates[skill]`` (the rate
an operator's plan cost is to come from) with ``measured[skill]``: the runs, successes,
the policy, the commands and the initial states. Refuses (exit 2) outputs of another
policy or without a run of the skill. Written atomically; MANIFEST is the training's
``--out`` folder's (the package refuses writes: the shipped folder is a copy of it).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from osg_control.execution.bundle import RATES_KEY
from osg_control.io_safety import atomic_write
from osg_control.libero.recording import OPERATORS


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("manifest", type=Path)
    parser.add_argument("bench", type=Path, nargs="+")
    parser.add_argument("--skill", choices=sorted(OPERATORS), default="pick")
    parser.add_argument("--command", required=True, help="the benchmark command(s) run")
    args = parser.parse_args(argv)
    runs = ok = 0
    where = []
    for path in args.bench:
        summary = json.loads(path.read_text())
        if summary.get("policy") != "skills":
            print(f"{path}: policy {summary.get('policy')!r}, not skills", file=sys.stderr)
            return 2
        for op in OPERATORS[args.skill]:
            row = summary["operators"].get(op, {"runs": 0, "ok": 0})
            runs, ok = runs + row["runs"], ok + row["ok"]
        tasks = {t: r["init_states"] for t, r in summary["tasks"].items()}
        where.append({"suite": summary["suite"], "seed": summary["seed"], "tasks": tasks})
    if not runs:
        print(f"no run of {args.skill} in {', '.join(map(str, args.bench))}", file=sys.stderr)
        return 2
    manifest = json.loads(args.manifest.read_text())
    manifest[RATES_KEY][args.skill] = round(ok / runs, 4)
    manifest.setdefault("measured", {})[args.skill] = {
        "runs": runs, "perceived_successes": ok, "policy": "skills",
        "command": args.command, "episodes": where,
    }  # fmt: skip
    text = json.dumps(manifest, indent=2) + "\n"
    atomic_write(args.manifest, lambda tmp: tmp.write_text(text))
    print(f"{args.skill}: {ok}/{runs} = {ok / runs:.3f} written to {args.manifest}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
