"""Measure whether the UR5, mounted where the kitchen puts it (or at ``--base``), reaches every
node of the home kitchen with the TCP pointing down, and what it touches there.

Usage: python tools/ur5_kitchen_reach.py [--base X Y Z] [--steps N] [--max-step M] [--json]
Per node: mink differential IK (``control.reach.reach_pose``: frame + posture tasks, joint
position and velocity limits, 50 ms steps, the target walking a straight line at most
``--max-step`` per step) from ``HOME_Q`` toward the node's pose, then the arm put there in
the kitchen scene (the door shut, then open; fingers open) and the geoms the robot touches
listed (the scene's and its own). Per skill: its waypoints reached in turn from its start node's
configuration, and what the robot touches along the way (every other step), the door open
where the skill starts with it open. Contacts with what the fingers grasp or push (the cube,
the door's handle, the valve's lever) are not counted; the scene stays still (the door does
not follow the hand in slide-door-open). Deterministic: no randomness.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from typing import Any

import mujoco
import numpy as np

from osg_control.control.description import Placement, RobotDescription, mounted
from osg_control.control.reach import Reach, reach_pose
from osg_control.control.robot_model import robot_spec
from osg_control.control.scene_model import with_robot
from osg_control.domain.spec import TOP_DOWN_QUAT
from osg_control.kitchen.domain import kitchen_domain
from osg_control.kitchen.scene import ROBOT_MOUNTS, kitchen_xml_path
from osg_control.kitchen.skills import NODES, SKILLS
from osg_control.robots import ur5_model
from osg_control.robots.registry import get_robot

KITCHEN_BASE = ROBOT_MOUNTS["ur5"]
"""The UR5's mount in the kitchen."""

MANIPULATED_GEOMS = frozenset({"cube", "handle", "valve_lever"})
"""What the fingers grasp or push: contacts with them are the skills' point."""
DOOR_OPEN = 0.45
HOME = kitchen_domain().home


def ur5_at(base: Placement) -> RobotDescription:
    """The UR5's description mounted at ``base``."""
    return mounted(get_robot("ur5"), base)


def kitchen_with_ur5(base: Placement) -> tuple[mujoco.MjModel, frozenset[int]]:
    """The kitchen with the UR5 mounted at ``base``; the robot's geom ids."""
    robot = ur5_at(base)
    alone = robot_spec(robot)
    robot_bodies = {body.name for body in alone.bodies} - {alone.worldbody.name}
    scene = with_robot(mujoco.MjSpec.from_file(str(kitchen_xml_path())), robot)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")
        model = scene.compile()
    geoms = frozenset(
        g for g in range(model.ngeom) if model.body(model.geom_bodyid[g]).name in robot_bodies
    )
    return model, geoms


def touched(
    model: mujoco.MjModel, robot_geoms: frozenset[int], path: np.ndarray, door: float
) -> list[str]:
    """The geoms the robot touches at any arm configuration of ``path`` (fingers open): the
    scene's and its own (the pairs the SRDF leaves on), as robot geom/other geom pairs with
    their deepest penetration [mm]."""
    data = mujoco.MjData(model)
    arm = [model.joint(name).qposadr[0] for name in ur5_model.ARM_JOINTS]
    for name in ur5_model.FINGER_JOINTS:
        data.qpos[model.joint(name).qposadr[0]] = ur5_model.FINGER_OPEN
    data.qpos[model.joint("door_slide").qposadr[0]] = door
    depth: dict[str, float] = {}
    for q in np.atleast_2d(path):
        data.qpos[arm] = q
        mujoco.mj_forward(model, data)
        for contact in data.contact[: data.ncon]:
            a, b = (int(g) for g in contact.geom)
            if a not in robot_geoms and b not in robot_geoms:
                continue  # the scene's own contacts (the cube on the counter)
            mine, other = (a, b) if a in robot_geoms else (b, a)
            if model.geom(other).name in MANIPULATED_GEOMS:
                continue
            pair = f"{_geom_name(model, mine)}/{_geom_name(model, other)}"
            depth[pair] = max(depth.get(pair, 0.0), -1000 * float(contact.dist))
    return [f"{name} ({depth[name]:.1f} mm)" for name in sorted(depth)]


def _geom_name(model: mujoco.MjModel, geom: int) -> str:
    """A geom's name, or its body's for an unnamed one (the URDF's meshes)."""
    return model.geom(geom).name or model.body(model.geom_bodyid[geom]).name


def reach_world(
    arm: mujoco.MjModel,
    position: tuple[float, float, float],
    orientation: tuple[float, ...],
    start_q: np.ndarray,
    steps: int,
    max_step: float | None,
) -> Reach:
    """``reach_pose`` toward a kitchen pose (``arm`` built at its placement)."""
    limits = dict(zip(ur5_model.ARM_JOINTS, ur5_model.velocity_limits(), strict=True))
    return reach_pose(
        arm,
        get_robot("ur5").tcp.site,
        position,
        orientation,
        start_q,
        limits,
        steps,
        max_step=max_step,
    )


def measure(
    steps: int, max_step: float, base: Placement = KITCHEN_BASE
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """One row per kitchen node (IK errors from ``HOME_Q``, the final q, what the robot
    touches there) and one per skill (its waypoints reached in turn from its start node's
    q: the worst error, what the robot touches along the way)."""
    arm = robot_spec(ur5_at(base), with_gripper=False).compile()
    scene, robot_geoms = kitchen_with_ur5(base)
    rows = []
    node_q = {}
    start = ur5_model.HOME_Q
    for name, node in NODES.items():  # home first: the others start from its solution
        reach = reach_world(arm, node.position, node.orientation, start, steps, max_step)
        start = node_q[HOME] if HOME in node_q else reach.q
        node_q[name] = reach.q
        rows.append(
            {
                "node": name,
                "position": list(node.position),
                "reached": reach.reached(),
                "position_error_m": reach.position_error,
                "orientation_error_rad": reach.orientation_error,
                "q": [round(float(v), 4) for v in reach.q],
                "touches_door_shut": touched(scene, robot_geoms, reach.q, 0.0),
                "touches_door_open": touched(scene, robot_geoms, reach.q, DOOR_OPEN),
            }
        )
    skill_rows = [
        skill_row(skill, arm, scene, robot_geoms, node_q, steps, max_step) for skill in SKILLS
    ]
    return rows, skill_rows


def skill_row(
    skill: Any,
    arm: mujoco.MjModel,
    scene: mujoco.MjModel,
    robot_geoms: frozenset[int],
    node_q: dict[str, np.ndarray],
    steps: int,
    max_step: float,
) -> dict[str, Any]:
    """A skill's waypoints reached in turn from its start node's q, the door open where the
    skill starts with it open."""
    door = DOOR_OPEN if "door-open" in skill.preconditions | skill.start_facts else 0.0
    q = node_q[skill.start]
    position_errors: list[float] = []
    orientation_errors: list[float] = []
    paths = []
    for waypoint in skill.waypoints:
        orientation = waypoint.orientation or TOP_DOWN_QUAT
        reach = reach_world(arm, waypoint.position, orientation, q, steps, max_step)
        position_errors.append(reach.position_error)
        orientation_errors.append(reach.orientation_error)
        paths.append(reach.path)
        q = reach.q
    return {
        "skill": skill.name,
        "door_open": bool(door),
        "reached": all(e <= 1e-3 for e in position_errors)
        and all(e <= 1e-2 for e in orientation_errors),
        "position_error_m": max(position_errors),
        "orientation_error_rad": max(orientation_errors),
        "touches": touched(scene, robot_geoms, np.concatenate(paths)[::2], door),
        "min_singular_value": min_singular_value(arm, np.concatenate(paths)),
    }


def min_singular_value(arm: mujoco.MjModel, path: np.ndarray) -> float:
    """The smallest singular value of the TCP's 6 x 6 Jacobian over ``path``: how far the
    arm stays from a singularity (the stretched elbow, the wrist, the shoulder)."""
    data = mujoco.MjData(arm)
    site = arm.site(get_robot("ur5").tcp.site).id
    jacobian = np.zeros((6, arm.nv))
    smallest = np.inf
    for q in path:
        data.qpos[:] = q
        mujoco.mj_kinematics(arm, data)
        mujoco.mj_comPos(arm, data)
        mujoco.mj_jacSite(arm, data, jacobian[:3], jacobian[3:], site)
        smallest = min(smallest, float(np.linalg.svd(jacobian, compute_uv=False)[-1]))
    return smallest


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--base",
        type=float,
        nargs=3,
        default=KITCHEN_BASE[0],
        metavar=("X", "Y", "Z"),
        help="the base link's position [m] (not rotated; default: the kitchen's mount)",
    )
    parser.add_argument("--steps", type=int, default=400, help="IK steps of 50 ms per node")
    parser.add_argument(
        "--max-step",
        type=float,
        default=kitchen_domain().action_bounds[0],
        help="the most the TCP target moves per 50 ms step [m] (default: the kitchen's "
        "action bound)",
    )
    parser.add_argument("--json", action="store_true", help="print the rows as JSON")
    args = parser.parse_args(argv)
    if args.steps < 1 or not args.max_step > 0 or not np.all(np.isfinite(args.base)):
        parser.error("--steps must be at least 1, --max-step positive and --base finite")
    base: Placement = ((args.base[0], args.base[1], args.base[2]), KITCHEN_BASE[1])
    rows, skill_rows = measure(args.steps, args.max_step, base)
    if args.json:
        print(json.dumps({"nodes": rows, "skills": skill_rows}, indent=2))
        return 0
    print(
        f"{'node':15s} {'reached':7s} {'pos err':>9s} {'rot err':>9s}  touches (door shut | open)"
    )
    for row in rows:
        print(
            f"{row['node']:15s} {str(row['reached']):7s} {row['position_error_m']:9.2e} "
            f"{row['orientation_error_rad']:9.2e}  {', '.join(row['touches_door_shut']) or '-'}"
            f" | {', '.join(row['touches_door_open']) or '-'}"
        )
    print(
        f"\n{'skill':22s} {'door':5s} {'reached':7s} {'pos err':>9s} {'rot err':>9s} "
        f"{'min sv':>6s}  touches"
    )
    for row in skill_rows:
        print(
            f"{row['skill']:22s} {'open' if row['door_open'] else 'shut':5s} "
            f"{str(row['reached']):7s} {row['position_error_m']:9.2e} "
            f"{row['orientation_error_rad']:9.2e} {row['min_singular_value']:6.3f}  "
            f"{', '.join(row['touches']) or '-'}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
