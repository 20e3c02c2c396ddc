"""Where the open hand must stay above the objects it passes: each object's perceived
footprint (``footprint``) and the least TCP height over a point on the way to a grasp
(``transit_height``), from the percept and the scene's geometry.

An approach that descended on a straight line from inside the basket to the next object
hooked the basket's rim and dragged it onto that object (LIBERO-10 task 7); the hand
now keeps above what it passes and goes down only over its goal.
"""

from __future__ import annotations

import numpy as np

from osg_control.libero.facts import region_pose
from osg_control.libero.legs import Context, yawed
from osg_control.libero.perception import LiberoPercept

HAND_MARGIN = 0.06
"""How far beyond the TCP the open fingers and the palm's lower edge reach sideways [m]."""
TRANSIT_CLEARANCE = 0.05
"""Height the TCP keeps above the top of an object it passes over [m]."""
HAND_BOXES = ((0.105, 0.032, 0.026), (0.055, 0.011, -0.012))
"""The open hand round the TCP, as robosuite's Panda gripper's collision geoms: the palm
and the open fingers, each (half-length along the fingers' sliding axis, half-width
across it, height of its lower face above the TCP) [m]."""


def posed_corners(ctx: Context, percept: LiberoPercept, obj: str, turn: float = 0.0) -> np.ndarray:
    """The 8 corners of ``obj``'s collision extent, about its origin, at its perceived
    rotation turned ``turn`` [rad] about the vertical first (world axes, 8 x 3)."""
    _, rot = percept.objects[obj]
    if turn:
        rot = yawed(turn) @ rot
    low, high = ctx.scene.extents[obj]
    corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                        for z in (low[2], high[2])])  # fmt: skip
    return corners @ rot.T


def footprint(ctx: Context, percept: LiberoPercept, obj: str, turn: float = 0.0) -> np.ndarray:
    """An object's perceived footprint: the world xy box (lower, upper) round its
    collision geometry (a moka pot's handle included), turned ``turn`` [rad] about the
    vertical through its origin first."""
    world = percept.position(obj)[:2] + posed_corners(ctx, percept, obj, turn)[:, :2]
    return np.array([world.min(axis=0), world.max(axis=0)])


def overlap(a: np.ndarray, b: np.ndarray, margin: float) -> bool:
    """Whether two xy boxes (lower, upper) come within ``margin`` of each other."""
    return bool(np.all(a[0] < b[1] + margin) and np.all(b[0] < a[1] + margin))


def carried(percept: LiberoPercept, held: str) -> np.ndarray:
    """The TCP minus the ``held`` object's perceived origin: where the hand is relative to
    what it carries (a target for the object plus this is the hand's)."""
    return percept.tcp - percept.position(held)


def hang(ctx: Context, percept: LiberoPercept, held: str) -> float:
    """How far the ``held`` object's bottom hangs below the TCP [m]."""
    return float(percept.tcp[2] - percept.position(held)[2] - ctx.scene.extents[held][0][2])


def transit_height(
    ctx: Context, percept: LiberoPercept, goal_xy: np.ndarray, held: str | None = None
) -> float:
    """The least TCP height where the hand is now, on its way to ``goal_xy``: its lowest
    point (the fingertips, or the bottom of the ``held`` object) ``TRANSIT_CLEARANCE``
    above the top of every object under it (the TCP, or the held object's footprint, within
    ``HAND_MARGIN`` of that object's footprint). The objects under the goal itself (what is
    grasped, what it stands in, where the held object goes) are left out: the hand goes
    down there. -inf when nothing is under."""
    tcp = percept.tcp
    here = np.array([tcp[:2], tcp[:2]])
    drop = 0.0  # how far the lowest point hangs below the TCP
    if held is not None:
        here = footprint(ctx, percept, held)
        drop = hang(ctx, percept, held)
    floor = -np.inf
    for obj in percept.objects:
        if obj == held:
            continue
        box = footprint(ctx, percept, obj)
        at_goal = overlap(box, np.array([goal_xy, goal_xy]), 0.0)
        if at_goal or not overlap(box, here, HAND_MARGIN):
            continue
        top = percept.position(obj)[2] + ctx.scene.extents[obj][1][2]
        floor = max(floor, top + TRANSIT_CLEARANCE + max(drop, 0.0))
    return float(floor)


def hand_clearance(
    ctx: Context, percept: LiberoPercept, tcp: np.ndarray, along: np.ndarray, obj: str
) -> float:
    """The least horizontal gap between the open hand (``HAND_BOXES``), its TCP at ``tcp``
    and its fingers sliding along ``along``, and the footprint of every object other than
    ``obj`` that rises above the hand's lower faces there (negative: they overlap). An
    object whose footprint holds the TCP (what ``obj`` stands in) is left out; inf when
    nothing is near."""
    obstacles = []
    for other in percept.objects:
        box = footprint(ctx, percept, other)
        if other == obj or overlap(box, np.array([tcp[:2], tcp[:2]]), 0.0):
            continue
        top = percept.position(other)[2] + ctx.scene.extents[other][1][2]
        corners = np.array([[box[i][0], box[j][1]] for i in (0, 1) for j in (0, 1)])
        obstacles.append((corners, float(top)))
    return _hand_gap(tcp, along, obstacles)


def fixture_clearance(
    ctx: Context, percept: LiberoPercept, tcp: np.ndarray, along: np.ndarray
) -> float:
    """``hand_clearance`` against the fixtures' regions (the scene's boxes, a drawer's at
    its sensed travel: a cabinet's drawers and top) that rise above the hand's lower
    faces: the fixtures' walls round them are not perceived otherwise."""
    obstacles = []
    for name, region in ctx.scene.regions.items():
        if region.carrier is not None:
            continue
        pos, mat = region_pose(ctx.scene, percept, name)
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        corners = pos + (signs * region.size) @ mat.T
        obstacles.append((corners[:, :2], float(corners[:, 2].max())))
    return _hand_gap(tcp, along, obstacles)


def box_clearance(
    tcp: np.ndarray, along: np.ndarray, boxes: list[tuple[np.ndarray, np.ndarray]]
) -> float:
    """``hand_clearance`` against world boxes (lower, upper corners) that rise above the
    hand's lower faces."""
    obstacles = []
    for low, high in boxes:
        corners = np.array([[low[0], low[1]], [low[0], high[1]], [high[0], low[1]], high[:2]])
        obstacles.append((corners, float(high[2])))
    return _hand_gap(tcp, along, obstacles)


def _hand_gap(
    tcp: np.ndarray, along: np.ndarray, obstacles: list[tuple[np.ndarray, float]]
) -> float:
    """The least horizontal gap between the open hand at ``tcp``, its fingers sliding
    along ``along``, and the obstacles (xy corners, top) that rise above its lower faces."""
    axis = np.asarray(along[:2], dtype=float) / np.linalg.norm(along[:2])
    across = np.array([-axis[1], axis[0]])
    least = np.inf
    for corners, top in obstacles:
        for half_along, half_across, lift in HAND_BOXES:
            if top <= tcp[2] + lift:
                continue
            hand = np.array([tcp[:2] + a * half_along * axis + b * half_across * across
                             for a in (-1, 1) for b in (-1, 1)])  # fmt: skip
            least = min(least, _separation(hand, corners, (axis, across)))
    return least


def _separation(a: np.ndarray, b: np.ndarray, axes: tuple[np.ndarray, ...]) -> float:
    """How far apart two convex xy polygons (corners) are along the separating axis that
    parts them most, of the world's two and ``axes`` (negative: the least overlap)."""
    gaps = []
    for u in (np.array([1.0, 0.0]), np.array([0.0, 1.0]), *axes):
        pa, pb = a @ u, b @ u
        gaps.append(max(pb.min() - pa.max(), pa.min() - pb.max()))
    return float(max(gaps))
