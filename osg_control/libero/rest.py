"""Where an object too wide for a fixture's compartment is set down: the spot of the
region where it comes to rest lowest on the fixture's collision geometry, its origin still
inside the region's box (LIBERO's ``In`` reads the origin). LIBERO-PRO's ``libero_10_task``
task 5 puts a 9.4 cm mug in the caddy's 5.5 cm back compartment: set down over the
region's floor it caught the taller back wall and fell off; resting on the low middle wall,
clear of the back one, its origin lies in the box.
"""

from __future__ import annotations

import numpy as np

from osg_control.libero.clearance import posed_corners
from osg_control.libero.facts import region_pose
from osg_control.libero.legs import Context, yawed
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.scene import Solid

SPOTS = 15
"""The region's footprint is searched over ``SPOTS`` x ``SPOTS`` origins."""
INSET = 0.003
"""How far inside the region's footprint the searched origins keep [m]."""
HEADROOM = 0.01
"""How far below the region's box top a resting origin must lie [m]."""
SPACING = 0.004
"""The largest gap between the points of a collision box its rest is computed at [m]
(the caddy's walls are 7-8 mm thick: 5 points along the book's 11 cm straddled them)."""
LEVEL = 0.002
"""Rests within this of the lowest count as equally low [m]."""


def too_wide(ctx: Context, percept: LiberoPercept, held_obj: str, target: str) -> bool:
    """Whether ``held_obj``, at its perceived pose, is wider than the fixture region
    ``target`` along either of the region's horizontal axes (its collision boxes' extent
    projected on them: a thin book turned 45 deg to the world has a wide world footprint
    and still fits a compartment it is turned along)."""
    box = ctx.scene.regions[target]
    if box.carrier is not None or box.joint is not None or box.parent not in ctx.scene.solids:
        return False
    _, mat = region_pose(ctx.scene, percept, target)
    corners = posed_corners(ctx, percept, held_obj)
    for axis in range(3):
        direction = mat[:, axis]
        if abs(direction[2]) > 0.5:  # the region's vertical axis
            continue
        spread = corners @ direction
        if float(spread.max() - spread.min()) > 2.0 * float(box.size[axis]):
            return True
    return False


def lowest_rest(
    ctx: Context, percept: LiberoPercept, held_obj: str, target: str
) -> np.ndarray | None:
    """The point ``held_obj`` is set down over in the fixture region ``target`` (its origin's
    xy; its bottom's height at rest): of the origins in the region's footprint
    (``INSET``) whose rest on the fixture (``rest_heights``) leaves the origin
    ``HEADROOM`` under the box's top, the lowest (within ``LEVEL``), the nearest the middle
    of those; None where none does."""
    pos, mat = region_pose(ctx.scene, percept, target)
    half = np.abs(mat @ ctx.scene.regions[target].size)
    grid = np.linspace(-1.0, 1.0, SPOTS)
    reach = np.maximum(half[:2] - INSET, 0.0)
    spots = np.array([pos[:2] + reach * (a, b) for a in grid for b in grid])
    solids = ctx.scene.solids[ctx.scene.regions[target].parent]
    rests = rest_heights(ctx, percept, held_obj, spots, solids)
    rests = np.maximum(rests, pos[2] - half[2])  # nothing below: its floor
    fits = rests <= pos[2] + half[2] - HEADROOM
    if not np.any(fits):
        return None
    low = fits & (rests <= np.min(rests[fits]) + LEVEL)
    middle = spots[low].mean(axis=0)
    best = int(np.argmin(np.where(low, np.linalg.norm(spots - middle, axis=1), np.inf)))
    bottom = float(ctx.scene.extents[held_obj][0][2])
    return np.r_[spots[best], rests[best] + bottom]


def rest_heights(
    ctx: Context, percept: LiberoPercept, held_obj: str, spots: np.ndarray, solids: list[Solid]
) -> np.ndarray:
    """The height [m] of ``held_obj``'s origin lowered upright, at its perceived yaw, over
    each xy of ``spots`` onto ``solids`` until one of its collision boxes (``Scene.shapes``,
    sampled ``SPACING`` apart, ``_lattice``) touches one; -inf where none is under it."""
    _, rot = percept.objects[held_obj]
    turn = yawed(float(np.arctan2(rot[1, 0], rot[0, 0])))
    local = _underside(np.concatenate([_lattice(shape) for shape in ctx.scene.shapes[held_obj]]))
    local = local @ turn.T
    xy = (spots[:, None, :] + local[None, :, :2]).reshape(-1, 2)
    near = [solid for solid in solids if _overlaps(solid, xy.min(axis=0), xy.max(axis=0))]
    tops = _tops(xy, near).reshape(len(spots), len(local))
    return np.max(tops - local[None, :, 2], axis=1)


def _lattice(shape: Solid) -> np.ndarray:
    """Points through ``shape``'s box, at most ``SPACING`` apart along each of its axes."""
    steps = [np.linspace(-h, h, max(2, int(np.ceil(2.0 * h / SPACING)) + 1)) for h in shape.half]
    grid = np.stack(np.meshgrid(*steps, indexing="ij"), axis=-1).reshape(-1, 3)
    return shape.centre + grid @ shape.rotation.T


def _overlaps(solid: Solid, low: np.ndarray, high: np.ndarray) -> bool:
    """Whether ``solid``'s xy bounds meet the xy box (``low``, ``high``)."""
    reach = np.abs(solid.rotation[:2]) @ solid.half
    centre = solid.centre[:2]
    return bool(np.all(centre - reach <= high) and np.all(centre + reach >= low))


def _underside(points: np.ndarray) -> np.ndarray:
    """The lowest of ``points`` in each vertical column ``SPACING`` / 2 wide (the kept points
    stand at most ``SPACING`` apart): lowered onto what is under it, a column touches first
    with its lowest point."""
    cells = np.round(points[:, :2] / (SPACING / 2.0)).astype(np.int64)
    order = np.lexsort((points[:, 2], cells[:, 1], cells[:, 0]))
    cells, points = cells[order], points[order]
    first = np.ones(len(points), dtype=bool)
    first[1:] = np.any(cells[1:] != cells[:-1], axis=1)
    return points[first]


def _tops(xy: np.ndarray, solids: list[Solid]) -> np.ndarray:
    """For each point of ``xy`` (N x 2), the highest z where the vertical line through it
    leaves one of ``solids`` (-inf: it meets none)."""
    best = np.full(len(xy), -np.inf)
    for solid in solids:
        offset = np.c_[xy, np.zeros(len(xy))] - solid.centre
        a = offset @ solid.rotation  # the line's point at z = 0, in the solid's axes
        b = solid.rotation[2]  # its direction (world up) in those axes
        lower, upper = np.full(len(xy), -np.inf), np.full(len(xy), np.inf)
        for i in range(3):
            if abs(b[i]) < 1e-9:
                outside = np.abs(a[:, i]) > solid.half[i]
                lower[outside], upper[outside] = np.inf, -np.inf
                continue
            ends = np.sort(np.c_[(-solid.half[i] - a[:, i]) / b[i],
                                 (solid.half[i] - a[:, i]) / b[i]], axis=1)  # fmt: skip
            lower, upper = np.maximum(lower, ends[:, 0]), np.minimum(upper, ends[:, 1])
        best = np.where(lower <= upper, np.maximum(best, upper), best)
    return best
