"""``osg robots``: every registered robot with its joints, limits, TCP and gripper."""

from __future__ import annotations

import argparse
import json

from osg_control.errors import OSGError


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``robots`` to the ``osg`` parser."""
    parser = subparsers.add_parser(
        "robots", help="list the registered robots (joints, limits, TCP, gripper)"
    )
    parser.add_argument("--json", action="store_true", help="print the descriptions as JSON")
    parser.set_defaults(func=run_robots)


def run_robots(args: argparse.Namespace) -> int:
    """Describe every registered robot, each checked against its models; one that cannot be
    loaded is listed with its error (exit 1) and the others still are."""
    from osg_control.robots.registry import get_robot, robot_names

    summaries, broken = [], []
    for name in robot_names():
        try:
            summaries.append(get_robot(name).to_dict())
        except OSGError as err:
            broken.append({"name": name, "error": str(err)})
    if args.json:
        print(json.dumps(summaries + broken, indent=2))
        return 1 if broken else 0
    for entry in broken:
        print(f"{entry['name']}: BROKEN: {entry['error']}")
    for s in summaries:
        print(f"{s['name']}: {s['summary']}")
        print(f"  joints ({len(s['joints'])}): {', '.join(s['joints'])}")
        print(f"  velocity limits [rad/s]: {s['velocity']}")
        print(f"  TCP: frame {s['tcp']['frame']} on body {s['tcp']['body']}")
        gripper = s["gripper"]
        print(
            f"  gripper: {len(gripper['joints'])} joints, opens {gripper['max_opening']} m, "
            f"{gripper['force']} N"
        )
        null_space = "yes" if s["redundant"] else "no (joint reset holds still)"
        print(f"  control {s['control_hz']} Hz; sensors {', '.join(s['sensors'])}")
        print(f"  null space under the TCP task: {null_space}")
    return 1 if broken else 0
