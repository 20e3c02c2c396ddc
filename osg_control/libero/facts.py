"""LIBERO's goal predicates read from percepts: what the plan executor checks each step
against, and the perceived state it replans from.

The tests are LIBERO's own (``envs/predicates``, ``object_states``, ``site_object``) on
perceived poses and the fixture sensor's readings: ``In`` = the object's origin inside the
region's box (its floor lowered 1 cm); ``On`` a region = the origin within the box's
footprint and 0-10 cm above its top; ``On`` an object = at or above its origin and within
``ON_RADIUS`` of it in xy; ``Open``/``Close``/``TurnOn``/``TurnOff`` = a joint past
LIBERO's thresholds (``scene.Joint``). LIBERO's contact tests are not perceived: an object
counts as resting where it is when the hand does not hold it (``held``).
"""

from __future__ import annotations

import numpy as np

from osg_control.libero.perception import LiberoPercept
from osg_control.libero.problem import Atom, LiberoProblem
from osg_control.libero.scene import HANDLE_DEPTH, Joint, Scene

ON_RADIUS = 0.03
"""LIBERO's ``On`` on an object: the origins within 3 cm in xy."""
ON_HEIGHT = 0.10
"""LIBERO's ``On`` on a region: the origin at most 10 cm above the region's top."""
IN_FLOOR = 0.01
"""LIBERO's ``In``: the region's floor lowered by 1 cm."""
HELD_MARGIN = 0.015
"""An object is held when the TCP is within this of its box [m] and the fingers are not
wide open (``OPEN_WIDTH``)."""
OPEN_WIDTH = 0.075
"""Fingers wider than this [m] hold nothing (robosuite's Panda opens to about 0.08)."""


def region_pose(scene: Scene, percept: LiberoPercept, name: str) -> tuple[np.ndarray, np.ndarray]:
    """A region's perceived centre and orientation: carried by its object's observed pose,
    or a fixture's, shifted along its drawer's axis by the sensed joint travel."""
    box = scene.regions[name]
    if box.carrier is not None:
        pos, rot = percept.objects[box.carrier]
        return pos + rot @ box.pos, rot @ box.mat
    if box.joint is None:
        return box.pos, box.mat
    joint = scene.joints[box.joint]
    return box.pos + joint.axis * (percept.joint(joint.name) - joint.q0), box.mat


def handle_at(scene: Scene, joint: Joint, q: float) -> np.ndarray:
    """A drawer's handle (its centre) when its joint is at ``q``."""
    return scene.handles[joint.name] + joint.axis * (q - joint.q0)


def room(scene: Scene, percept: LiberoPercept, region: str) -> tuple[float, float]:
    """The stretch of the drawer ``region`` open from above at its sensed travel, as
    (back, front) along its pull: from the region's front edge back to the front of the
    handles of the drawers above it (at their sensed travel) or of its own handle shut
    (the cabinet's front), whichever stands further out (a handle's front taken
    ``HANDLE_DEPTH`` before its centre), or to the region's back edge."""
    box = scene.regions[region]
    joint = scene.joints[str(box.joint)]
    out = joint.outward
    pos, mat = region_pose(scene, percept, region)
    half = float(np.abs(mat @ box.size) @ np.abs(out))
    own = scene.handles[joint.name][2]
    above = [scene.joints[str(r.joint)] for r in scene.regions.values()
             if r.parent == box.parent and r.joint is not None and r.joint != box.joint
             and scene.handles[str(r.joint)][2] > own]  # fmt: skip
    fronts = [handle_at(scene, joint, joint.shut) @ out]
    fronts += [handle_at(scene, j, percept.joint(j.name)) @ out for j in above]
    back = max(float(max(fronts)) + HANDLE_DEPTH, float(pos @ out) - half)
    return back, float(pos @ out) + half


def held(scene: Scene, percept: LiberoPercept, obj: str) -> bool:
    """Whether the hand holds ``obj``: the fingers not wide open and the TCP at its box."""
    if percept.finger_width > OPEN_WIDTH or obj not in percept.objects:
        return False
    pos, rot = percept.objects[obj]
    low, high = scene.extents[obj]
    local = rot.T @ (percept.tcp - pos)
    return bool(np.linalg.norm(local - np.clip(local, low, high)) < HELD_MARGIN)


def in_region(scene: Scene, percept: LiberoPercept, obj: str, region: str) -> bool:
    """LIBERO's ``In`` (a region's contact test is always true in LIBERO)."""
    pos, mat = region_pose(scene, percept, region)
    half = np.abs(mat @ scene.regions[region].size)
    low = pos - half
    low[2] -= IN_FLOOR
    return bool(np.all(percept.position(obj) > low) and np.all(percept.position(obj) < pos + half))


def on(scene: Scene, percept: LiberoPercept, obj: str, target: str) -> bool:
    """LIBERO's ``On``, its contact test read as "not held"."""
    if held(scene, percept, obj):
        return False
    p = percept.position(obj)
    if target in scene.regions:
        pos, mat = region_pose(scene, percept, target)
        size = scene.regions[target].size
        delta = mat @ (p - pos)  # as LIBERO's SiteObject.under
        return bool(size[2] - 0.005 < delta[2] < size[2] + ON_HEIGHT
                    and np.all(np.abs(delta[:2]) < size[:2]))  # fmt: skip
    if target not in percept.objects:
        return False
    t = percept.position(target)
    return bool(t[2] <= p[2] and np.linalg.norm(p[:2] - t[:2]) < ON_RADIUS)


def _joint_state(scene: Scene, percept: LiberoPercept, thing: str, active: bool) -> bool:
    joints = [scene.joints[j] for j in scene.articulated.get(thing, ())]
    if not joints:
        return False
    if active:  # LIBERO: open / on when any joint is
        return any(j.is_active(percept.joint(j.name)) for j in joints)
    return all(j.is_rest(percept.joint(j.name)) for j in joints)


def _half_open(scene: Scene, percept: LiberoPercept, thing: str) -> bool:
    """Whether any joint of ``thing`` is perceived past the middle of its LIBERO thresholds."""
    joints = [scene.joints[j] for j in scene.articulated.get(thing, ())]
    return any((percept.joint(j.name) - (j.active + j.rest) / 2) * j.opening > 0 for j in joints)


def holds(scene: Scene, percept: LiberoPercept, atom: Atom) -> bool:
    """Whether a goal atom holds in the percept (False for a predicate it cannot read)."""
    args = atom.args
    if atom.predicate == "in":
        return args[1] in scene.regions and in_region(scene, percept, *args)
    if atom.predicate == "on":
        return on(scene, percept, *args)
    if atom.predicate in ("open", "turnon"):
        return _joint_state(scene, percept, args[0], active=True)
    if atom.predicate in ("close", "turnoff"):
        return _joint_state(scene, percept, args[0], active=False)
    return False


def perceived_init(
    problem: LiberoProblem, scene: Scene, percept: LiberoPercept
) -> tuple[Atom, ...]:
    """The state to plan from, read from the percept: each movable object's supports
    (``in``/``on`` every region or other object it perceivably is in or on), and the
    drawers, doors and knobs perceived open or on (``articulation.implied_init`` adds the
    rest). An object perceived on no support keeps the task file's support atoms: the
    table's start regions are small boxes round the starting spots, and ``pick`` needs a
    support only as its precondition. A drawer, door or knob between LIBERO's thresholds
    is stated as the goal does not want it, so that the plan moves it; but a drawer the
    goal puts something in is open when more than half-way open (a closed drawer's noisy
    reading straddles its closed threshold, and read as half-way, so open, half the time;
    LIBERO-10's open drawer starts 1-12 mm past its open threshold), until that object is
    perceived in it: a drawer pushed short of its closed threshold with the bowl inside
    then read as closed, the plan was empty and the drawer never closed."""
    atoms: list[Atom] = []
    for obj in problem.objects:
        if obj not in percept.objects:
            continue
        mine = []
        for thing in (*scene.regions, *percept.objects):
            region = scene.regions.get(thing)
            if thing == obj or (region is not None and region.parent == obj):
                continue
            if region is not None and in_region(scene, percept, obj, thing):
                mine.append(Atom("in", (obj, thing)))
            if on(scene, percept, obj, thing):
                mine.append(Atom("on", (obj, thing)))
        if not mine:
            mine = [a for a in problem.init if a.predicate in ("on", "in") and a.args[0] == obj]
        atoms += mine
    wanted = {a.args[0] for a in problem.goal if a.predicate in ("open", "turnon")}
    filled = {  # drawers the goal still has to fill
        a.args[1] for a in problem.goal
        if a.predicate == "in" and not holds(scene, percept, a)
    }  # fmt: skip
    for thing in scene.articulated:
        predicate = "turnon" if thing in scene.knobs else "open"
        if thing in wanted:  # open / on only when perceived past LIBERO's threshold
            active = _joint_state(scene, percept, thing, active=True)
        elif thing in filled:  # open when more than half-way: the hand gets in
            active = _half_open(scene, percept, thing)
        else:  # half-way counts as open / on: it still has to be closed / turned off
            active = not _joint_state(scene, percept, thing, active=False)
        if active:
            atoms.append(Atom(predicate, (thing,)))
    return tuple(atoms)
