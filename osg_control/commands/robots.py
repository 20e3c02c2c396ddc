"""``osg robots``: every registered robot with its joints, limits, TCP and gripper."""

from __future__ import annotations

import argparse
from typing import Any

from osg_control.commands.listing import add_listing_verb


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``robots [--json]`` to the ``osg`` parser: every registered robot, checked
    against its models; one that cannot be loaded is listed with its error (exit 1)."""
    add_listing_verb(
        subparsers,
        "robots",
        "list the registered robots (joints, limits, TCP, gripper)",
        _robot_names,
        _describe,
        _print_robot,
    )


def _robot_names() -> list[str]:
    from osg_control.robots.registry import robot_names

    return robot_names()


def _describe(name: str) -> dict[str, Any]:
    from osg_control.robots.registry import get_robot

    return get_robot(name).to_dict()


def _print_robot(s: dict[str, Any]) -> None:
    print(f"{s['name']}: {s['summary']}")
    print(f"  joints ({len(s['joints'])}): {', '.join(s['joints'])}")
    print(f"  velocity limits [rad/s]: {s['velocity']}")
    print(f"  TCP: frame {s['tcp']['frame']} on body {s['tcp']['body']}")
    gripper = s["gripper"]
    print(
        f"  gripper: {len(gripper['joints'])} joints, opens {gripper['max_opening']} m, "
        f"{gripper['force']} N"
    )
    null_space = "yes" if s["redundant"] else "no (the joint reset holds still)"
    print(f"  control {s['control_hz']} Hz; sensors {', '.join(s['sensors'])}")
    print(f"  null space under the TCP task: {null_space}")
