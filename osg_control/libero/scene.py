"""A LIBERO scene's static description, read once after the reset to an initial state.

What does not move during an episode (or moves only with a fixture joint the perception
layer senses) is read once from the env's model as the scene's description, the way a map
is given to a robot: each region's box (LIBERO's ``SiteObject``: its size, its pose in the
frame of the movable object that carries it, or in the world for a fixture's region, and
the drawer joint it slides with), each fixture joint (its axis, its anchor, LIBERO's own
open / close / on / off thresholds as data: ``object_properties["articulation"]``), a door's
leaf and a knob's grip point, and each movable object's extent in its own frame. Nothing
here is read again while deciding: object poses come from the observation, joint values
from the fixture sensor (``perception``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

JOINT_SLIDE, JOINT_HINGE = "slide", "hinge"
HANDLE_DEPTH = 0.015
"""How far behind a drawer's outermost point its handle's geoms may reach [m]."""
KNOB_DEPTH = 0.015
"""How far below the top of a knob's grip the TCP closes [m] (the fingertips reach about
1 cm further down, still above the knob's base plate)."""


@dataclass(frozen=True)
class Solid:
    """A collision geom's bounding box in a frame (the world's, or an object's upright
    frame): its ``centre`` [m], ``rotation`` (its axes as columns) and ``half`` sizes along
    them [m]."""

    centre: np.ndarray
    rotation: np.ndarray
    half: np.ndarray


@dataclass(frozen=True)
class RegionBox:
    """One region of the task file as LIBERO's predicates test it.

    Attributes:
        name: the region (``<parent>_<region>``).
        parent: the movable object or fixture it belongs to.
        carrier: the movable object whose observed pose carries it, or None (a fixture's
            region: ``pos``/``mat`` are then in the world at the reading).
        pos, mat: the site's pose in the carrier's frame (or the world's).
        size: the box's half sizes (LIBERO's site size).
        joint: the fixture joint it slides with (a drawer), or None.
    """

    name: str
    parent: str
    carrier: str | None
    pos: np.ndarray
    mat: np.ndarray
    size: np.ndarray
    joint: str | None


@dataclass(frozen=True)
class Joint:
    """A fixture joint (drawer slide, door hinge, knob) with LIBERO's thresholds.

    Attributes:
        name: the MuJoCo joint.
        kind: ``slide`` or ``hinge``.
        axis: its world axis; anchor: a point on it [m].
        q0: its value when the scene was read (the region and leaf poses are at ``q0``).
        active: the value past which it counts as open / on (the edge of LIBERO's open or
            turn-on range nearest the other range), or None when it has none.
        rest: the value past which it counts as closed / off (likewise).
        limits: its range.
    """

    name: str
    kind: str
    axis: np.ndarray
    anchor: np.ndarray
    q0: float
    active: float
    rest: float
    limits: tuple[float, float]

    @property
    def shut(self) -> float:
        """The end of its range that closes it (a door's or drawer's closed stop)."""
        return self.limits[1] if self.opening < 0 else self.limits[0]

    @property
    def opening(self) -> float:
        """+1 when opening increases the joint value, -1 when it decreases it."""
        return 1.0 if self.active > self.rest else -1.0

    @property
    def outward(self) -> np.ndarray:
        """The world direction a drawer comes out along (its axis, signed by ``opening``)."""
        return self.axis * self.opening

    def is_active(self, q: float) -> bool:
        """Open / on by LIBERO's rule (strictly past ``active``)."""
        return bool((q - self.active) * self.opening > 0)

    def is_rest(self, q: float) -> bool:
        """Closed / off by LIBERO's rule (strictly past ``rest``, away from ``active``)."""
        return bool((self.rest - q) * self.opening > 0)


@dataclass(frozen=True)
class Scene:
    """The static description of one episode's scene.

    Attributes:
        regions: region name -> its box.
        joints: fixture joint name -> the joint.
        articulated: an openable or turnable thing (a drawer region, a door or knob
            fixture) -> its joints (LIBERO: open if any is open, closed if all are).
        leaves: a door fixture -> its leaf's point furthest from the hinge at ``q0``
            (world) [m].
        knobs: a knob fixture -> its grip point at ``q0`` (world) [m]: on the knob's axis,
            ``KNOB_DEPTH`` below the top of its grip (its tallest geom).
        grips: a knob fixture -> the horizontal direction across its grip at ``q0`` (the
            fingers close along it; world, unit).
        handles: a drawer's slide joint -> its handle's centre at ``q0`` (world) [m].
        extents: movable object -> (lower, upper) corners of its collision geometry in its
            upright frame [m].
        parts: movable object -> the (lower, upper) corners of each of its collision
            geoms' boxes in its upright frame [m] (where a hand fits round it).
        frames: movable object -> its upright frame in its body frame (``upright_axes``):
            LIBERO's assets are modelled with any axis up (a can lying on its side has
            its body z horizontal); objects' poses, extents and regions are read in it.
        walls: a door fixture -> the world box (lower, upper) of each of its collision
            geoms other than its leaf's [m] (its ``housings`` round them all; the opening
            behind its door, ``insert.doorway``).
        shapes: movable object -> each of its collision geoms' bounding box as a ``Solid``
            in its upright frame (what it rests on a fixture with, ``rest``).
        solids: a fixture without joints (a caddy, a table) -> each of its collision geoms'
            bounding box as (centre [m], rotation, half-sizes [m]) in the world (what an
            object set down in one of its compartments rests on, ``rest``).
    """

    regions: dict[str, RegionBox]
    joints: dict[str, Joint]
    articulated: dict[str, tuple[str, ...]]
    leaves: dict[str, np.ndarray]
    knobs: dict[str, np.ndarray]
    grips: dict[str, np.ndarray]
    handles: dict[str, np.ndarray]
    extents: dict[str, tuple[np.ndarray, np.ndarray]]
    parts: dict[str, list[tuple[np.ndarray, np.ndarray]]]
    frames: dict[str, np.ndarray]
    walls: dict[str, list[tuple[np.ndarray, np.ndarray]]] = field(default_factory=dict)
    solids: dict[str, list[Solid]] = field(default_factory=dict)
    shapes: dict[str, list[Solid]] = field(default_factory=dict)

    @property
    def housings(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """A door fixture -> the world box (lower, upper) round its ``walls``: the body a
        thing carried to its doorway passes over."""
        return {name: (np.min([lo for lo, _ in boxes], axis=0),
                       np.max([hi for _, hi in boxes], axis=0))
                for name, boxes in self.walls.items() if boxes}  # fmt: skip


def upright_axes(rotation: np.ndarray) -> np.ndarray:
    """The signed permutation of a body's axes whose third is the one nearest the world's
    vertical, pointing up (a right-handed frame): the object's upright frame is then
    ``rotation @ upright_axes(rotation)``, its z up as long as the object stays upright."""
    up = int(np.argmax(np.abs(rotation[2])))
    first, second = (i for i in range(3) if i != up)
    axes = np.zeros((3, 3))
    axes[first, 0], axes[second, 1] = 1.0, 1.0
    axes[up, 2] = np.sign(rotation[2, up]) or 1.0
    if np.linalg.det(axes) < 0:
        axes[:, 0] *= -1.0
    return axes


def _subtree(model: Any, root: int) -> list[int]:
    bodies = [root]
    for body in range(model.nbody):
        if body != root and model.body_parentid[body] in bodies:
            bodies.append(body)
    return bodies


def _collision_geoms(model: Any, bodies: list[int]) -> list[int]:
    """The geoms of ``bodies`` that collide."""
    return [geom for geom in range(model.ngeom) if model.geom_bodyid[geom] in bodies
            and (model.geom_contype[geom] or model.geom_conaffinity[geom])]  # fmt: skip


def _geom_boxes(model: Any, data: Any, bodies: list[int]) -> list[np.ndarray]:
    """World corners (8 x 3) of each collision geom's bounding box of ``bodies``."""
    boxes = []
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    for geom in _collision_geoms(model, bodies):
        centre, half = model.geom_aabb[geom][:3], model.geom_aabb[geom][3:]
        local = centre + signs * half
        boxes.append(data.geom_xpos[geom] + local @ data.geom_xmat[geom].reshape(3, 3).T)
    return boxes


def _geom_solids(model: Any, data: Any, bodies: list[int]) -> list[Solid]:
    """Each collision geom's bounding box of ``bodies`` as a world ``Solid``."""
    solids = []
    for geom in _collision_geoms(model, bodies):
        rotation = data.geom_xmat[geom].reshape(3, 3).copy()
        centre = data.geom_xpos[geom] + rotation @ model.geom_aabb[geom][:3]
        solids.append(Solid(centre, rotation, model.geom_aabb[geom][3:].copy()))
    return solids


def _geom_corners(model: Any, data: Any, bodies: list[int]) -> np.ndarray:
    """World corners of the collision geoms' bounding boxes of ``bodies``."""
    boxes = _geom_boxes(model, data, bodies)
    return np.concatenate(boxes) if boxes else np.zeros((0, 3))


def _handle(model: Any, data: Any, joint: Joint) -> np.ndarray:
    """A drawer's handle at ``q0``: the centre of the moving part's geoms that reach
    furthest out along its opening direction (within ``HANDLE_DEPTH`` of the furthest)."""
    body = int(model.jnt_bodyid[model.joint(joint.name).id])
    boxes = _geom_boxes(model, data, _subtree(model, body))
    out = joint.outward
    reach = [float((box @ out).max()) for box in boxes]
    front = [box.mean(axis=0) for box, r in zip(boxes, reach, strict=True)
             if r > max(reach) - HANDLE_DEPTH]  # fmt: skip
    return np.mean(front, axis=0)


def _knob_grip(model: Any, data: Any, joint: Joint) -> tuple[np.ndarray, np.ndarray]:
    """A knob's grip point and the direction across its grip: its tallest collision geom is
    the grip (a bar standing on the knob's base plate); the point is where the knob's axis
    passes through the bar's centre line, ``KNOB_DEPTH`` below its top; the fingers close
    across the bar's narrower horizontal side."""
    body = int(model.jnt_bodyid[model.joint(joint.name).id])
    bodies = _subtree(model, body)
    geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] in bodies
             and (model.geom_contype[g] or model.geom_conaffinity[g])]  # fmt: skip
    boxes = _geom_boxes(model, data, bodies)
    tallest = int(np.argmax([np.ptp(box[:, 2]) for box in boxes]))
    geom, top = geoms[tallest], float(boxes[tallest][:, 2].max())
    rot = data.geom_xmat[geom].reshape(3, 3)
    half = model.geom_aabb[geom][3:]
    centre = data.geom_xpos[geom] + rot @ model.geom_aabb[geom][:3]
    flat = [i for i in range(3) if abs(rot[2, i]) < 0.7]  # the local axes lying horizontal
    along = rot[:, max(flat, key=lambda i: half[i])] * np.array([1.0, 1.0, 0.0])
    along /= np.linalg.norm(along)
    point = centre + along * float((joint.anchor - centre) @ along)
    return np.r_[point[:2], top - KNOB_DEPTH], np.cross([0.0, 0.0, 1.0], along)


def _thresholds(fixture: Any) -> tuple[float, float] | None:
    """(active, rest) from LIBERO's articulation ranges: the edge of each range nearest
    the other (its ``is_open``/``is_close``/``turn_on``/``turn_off`` compare to these)."""
    art = fixture.object_properties.get("articulation", {})
    for on_key, off_key in (
        ("default_open_ranges", "default_close_ranges"),
        ("default_turnon_ranges", "default_turnoff_ranges"),
    ):
        on, off = art.get(on_key), art.get(off_key)
        if on and off:
            if min(on) > max(off):
                return float(min(on)), float(max(off))
            return float(max(on)), float(min(off))
    return None


def _joint(model: Any, data: Any, name: str, fixture: Any) -> Joint | None:
    jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
    thresholds = _thresholds(fixture)
    if jid < 0 or thresholds is None:
        return None
    kind = {int(mujoco.mjtJoint.mjJNT_SLIDE): JOINT_SLIDE, int(mujoco.mjtJoint.mjJNT_HINGE):
            JOINT_HINGE}.get(int(model.jnt_type[jid]))  # fmt: skip
    if kind is None:
        return None
    return Joint(
        name, kind, data.xaxis[jid].copy(), data.xanchor[jid].copy(),
        float(data.qpos[model.jnt_qposadr[jid]]), thresholds[0], thresholds[1],
        (float(model.jnt_range[jid][0]), float(model.jnt_range[jid][1])),
    )  # fmt: skip


def read_scene(env: Any, problem: Any) -> Scene:
    """Describe the scene of a LIBERO env (``LiberoEnv.env``'s inner env) just reset, for
    the task ``problem``: its regions, fixture joints, doors, knobs and object extents."""
    inner = env.env
    model, data = inner.sim.model._model, inner.sim.data._data
    joints: dict[str, Joint] = {}
    articulated: dict[str, tuple[str, ...]] = {}
    leaves: dict[str, np.ndarray] = {}
    walls: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    knobs: dict[str, np.ndarray] = {}
    grips: dict[str, np.ndarray] = {}
    solids: dict[str, list[Solid]] = {}
    for name in problem.fixtures:
        fixture = inner.get_object(name)
        found = [_joint(model, data, j, fixture) for j in getattr(fixture, "joints", None) or ()]
        mine = [j for j in found if j is not None]
        joints.update({j.name: j for j in mine})
        if not mine:
            if fixture is not None:  # a table has no object: nothing is set down in it
                root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, fixture.root_body)
                solids[name] = _geom_solids(model, data, _subtree(model, root))
            continue
        moving = model.jnt_bodyid[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, mine[0].name)]
        leaf = _subtree(model, int(moving))
        corners = _geom_corners(model, data, leaf)
        if hasattr(fixture, "turn_on"):
            articulated[name] = tuple(j.name for j in mine)
            knobs[name], grips[name] = _knob_grip(model, data, mine[0])
        elif all(j.kind == JOINT_HINGE for j in mine) and len(mine) == 1:
            articulated[name] = (mine[0].name,)
            radial = corners - mine[0].anchor
            radial -= np.outer(radial @ mine[0].axis, mine[0].axis)
            leaves[name] = corners[int(np.argmax(np.linalg.norm(radial, axis=1)))]
            root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, fixture.root_body)
            body = _geom_boxes(model, data, [b for b in _subtree(model, root) if b not in leaf])
            walls[name] = [(box.min(axis=0), box.max(axis=0)) for box in body]
    frames = {
        obj: upright_axes(data.xmat[inner.obj_body_id[obj]].reshape(3, 3))
        for obj in problem.objects
    }
    regions: dict[str, RegionBox] = {}
    for region_name, region in problem.regions.items():
        site = inner.object_sites_dict.get(region_name)
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, region_name)
        if site is None or sid < 0:
            continue
        pos, mat = data.site_xpos[sid].copy(), data.site_xmat[sid].reshape(3, 3).copy()
        carrier = region.parent if region.parent in problem.objects else None
        if carrier is not None:
            body = inner.obj_body_id[carrier]
            rot = data.xmat[body].reshape(3, 3) @ frames[carrier]
            pos, mat = rot.T @ (pos - data.xpos[body]), rot.T @ mat
        slides = [j for j in getattr(site, "joints", None) or () if j in joints]
        if slides:
            articulated[region_name] = tuple(slides)
        regions[region_name] = RegionBox(
            region_name, region.parent, carrier, pos, mat, np.asarray(site.size, dtype=float),
            slides[0] if slides else None,
        )  # fmt: skip
    parts: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    shapes: dict[str, list[Solid]] = {}
    for obj in problem.objects:
        body = inner.obj_body_id[obj]
        rot = data.xmat[body].reshape(3, 3) @ frames[obj]  # the upright frame
        tree = _subtree(model, body)
        boxes = _geom_boxes(model, data, tree)
        local = [(box - data.xpos[body]) @ rot for box in boxes]
        parts[obj] = [(box.min(axis=0), box.max(axis=0)) for box in local]
        shapes[obj] = [Solid(rot.T @ (solid.centre - data.xpos[body]), rot.T @ solid.rotation,
                             solid.half) for solid in _geom_solids(model, data, tree)]  # fmt: skip
    extents = {
        obj: (np.min([lo for lo, _ in boxes], axis=0), np.max([hi for _, hi in boxes], axis=0))
        for obj, boxes in parts.items()
    }
    handles = {
        name: _handle(model, data, joint)
        for name, joint in joints.items()
        if joint.kind == JOINT_SLIDE
    }
    return Scene(regions, joints, articulated, leaves, knobs, grips, handles, extents, parts,
                 frames, walls, solids, shapes)  # fmt: skip
