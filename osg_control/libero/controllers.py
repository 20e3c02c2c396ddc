"""Scripted controllers for the operators of the lifted domain ``osg-libero``:
``operator_legs`` picks the one for a ground operator, which turns it into legs of TCP
motion (``legs``), every target computed from the current percept
(``perception.LiberoPercept``) and the scene's static description, driven by our IK
(``drive.JointTargetDriver``). Objects are moved by ``pick_place`` (grasps from
``grasp``), drawers, doors and knobs by ``fixtures``.

They are the first skills the plans run and the scripted collectors Algorithm 1's data
will come from: told which operator to run, they script its motion; they are not learned.

- ``approach ?x``: hover above ``?x`` (its grasp point, region, handle, knob or door),
  the hand and what it holds kept clear above the objects on the way (``clearance``).
- ``retreat ?x``: straight up to the home height (the node ``home`` is the safe height,
  not a fixed pose: going back to one would spend the step budget).
- ``pick ?o ?s`` / ``pick-out ?o ?r``: down to the grasp point, close, lift. A bowl is
  grasped at its rim (``RIM_GRASP``), anything else near its origin where the open hand
  clears its neighbours (``grasp.chosen_grip``; another grasp after a failed pick).
- ``approach ?r`` holding an object / ``place-in ?o ?r`` into a region behind a door (the
  microwave's, roofed): in front of the doorway, then in through it sideways (``insert``;
  the object was grasped for it when picked).
- ``place-on ?o ?t`` / ``place-in ?o ?r``: over the target so the held object's origin is
  above the target's, lower until its bottom is ``DROP`` above the surface (``on``) or the
  region's floor (``in``), open, up.
- ``open`` / ``close ?x ?r`` on a drawer: grasp its handle and pull past LIBERO's open
  threshold, or push its front to the closed stop with the closed hand.
- ``close ?x ?r`` on a door: push its leaf round the hinge, the push point leading the
  sensed door angle.
- ``turn-on`` / ``turn-off ?f``: grasp the knob and turn the wrist about the knob's axis
  until the sensed angle is past LIBERO's threshold.
"""

from __future__ import annotations

from osg_control.libero import insert
from osg_control.libero.fixtures import door, drawer, knob
from osg_control.libero.legs import Context, Leg
from osg_control.libero.operators import PICKS, PLACES
from osg_control.libero.pick_place import approach, pick, place, retreat


def operator_legs(
    ctx: Context, operator: str, args: tuple[str, ...], holding: str | None
) -> list[Leg]:
    """The legs of one ground operator of ``osg-libero``.

    Raises:
        KeyError: an operator no controller runs, or a thing the scene does not describe.
    """
    into_doorway = insert.doorway(ctx.scene, args[-1]) is not None
    if operator == "approach" and holding is not None and into_doorway:
        return insert.approach(ctx, args[0], holding)
    if operator == "approach":
        return approach(ctx, args[0], holding)
    if operator == "retreat":
        return retreat(ctx, holding)
    if operator in PICKS:
        return pick(ctx, args[0])
    if operator == "place-in" and into_doorway:
        return insert.insert(ctx, args[0], args[1])
    if operator in PLACES:
        return place(ctx, args[0], args[1], inside=operator == "place-in")
    if operator in ("open", "close") and args[0] in ctx.scene.leaves and operator == "close":
        return door(ctx, args[0])
    if operator in ("open", "close") and args[0] in ctx.scene.regions:
        return drawer(ctx, args[0], opening=operator == "open")
    if operator in ("turn-on", "turn-off"):
        return knob(ctx, args[0], on=operator == "turn-on")
    raise KeyError(f"no controller runs ({operator} {' '.join(args)})")
