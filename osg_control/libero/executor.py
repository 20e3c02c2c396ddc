"""Plan execution in LIBERO's envs: plan the task file's goal over ``osg-libero`` from the
perceived state, run the plan operator by operator with the scripted controllers
(``controllers``), check each operator's effect on the percept (``facts``), and on a failed
effect let go, lift, and replan from what is perceived then.

The policy ``scripted-plan`` of ``osg --domain libero evaluate benchmark``: its operators
are scripted controllers, not learned skills. It decides from percepts only; the env's
``check_success()`` scores it (``benchmark``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from osg_control.control.description import RobotDescription
from osg_control.control.ik_backends import IKConfig
from osg_control.libero.controllers import operator_legs
from osg_control.libero.drive import GRIPPER_OPEN, JointTargetDriver
from osg_control.libero.edge import edge_grasps, pinched_last
from osg_control.libero.facts import held, holds, perceived_init
from osg_control.libero.insert import doorway_grasps
from osg_control.libero.legs import Context, Leg, LegRunner, Runner, hold, up
from osg_control.libero.operators import PICKS, PLACES
from osg_control.libero.perception import LiberoPercept
from osg_control.libero.pick_place import holding_ok
from osg_control.libero.plan import plan_holds, plan_task
from osg_control.libero.problem import Atom, LiberoProblem
from osg_control.libero.scene import Scene
from osg_control.libero.tall import neck_grasps
from osg_control.libero.tip import tipped
from osg_control.planning.task import SearchLimits

MAX_REPLANS = 4
"""Replans an episode may make before the executor holds still."""
POSTURE_COST = 0.01
"""The IK's pull toward the arm's home posture (``control.ik_backends.IKConfig``): ten
times its default, so the arm stays near it over the whole plan. At the default the forearm
drifted down onto the cabinet while pushing a bottom drawer shut, and the first and third
joints wound up against each other (1.1 and -1.0 rad) until a pick close to the arm's base
folded the elbow near its limit and its descent crawled (6 cm in 40 steps)."""
FIXTURE_POSTURE_COST = 0.001
"""The posture pull while a drawer, door or knob is approached and worked
(``FIXTURE_OPERATORS``): the fixture controllers' legs were written at it; at
``POSTURE_COST`` the level hand's pull on LIBERO-Goal's middle drawer stopped short of the
open threshold."""
FIXTURE_OPERATORS = frozenset({"open", "close", "turn-on", "turn-off"})
CARRIES = frozenset({"approach", "retreat"})
"""The operators that move the hand with what it holds, if anything."""
SETTLED = 0.002
"""How far an object may move between two percepts [m] for the scene to count as at rest:
the first operator waits for it (``SETTLE_STEPS`` at most). LIBERO's initial states start
some objects moving (LIBERO-10 task 0's cartons thrown 30 cm up for 15 steps); the hand at
its transit pace met the soup can in the air and knocked it 14 cm away."""
SETTLE_STEPS = 30
"""The most steps the first operator waits for the scene to come to rest."""
DROPPED_STEPS = 3
"""Steps a held object must be perceived out of the hand (``facts.held``) for the carry to
count as failed. An edge-pinched can that slid out of the fingers just after its pick was
carried as if held for 130 steps, the carry rising to 1.27 m over it (its hang below the
hand grew as the hand rose: ``clearance.transit_height``), and set down for 110 more."""
PLAN_TIME_S = 30.0
"""A search's time limit [s]."""
EFFECTS: dict[str, tuple[str, int]] = {
    "place-on": ("on", 2), "place-in": ("in", 2), "open": ("open", 1), "close": ("close", 1),
    "turn-on": ("turnon", 1), "turn-off": ("turnoff", 1),
}  # fmt: skip
"""Operator -> the goal predicate its effect makes true, and how many of its arguments
that atom takes (``approach``/``retreat`` have none but, holding something, that it is
still held; ``pick``'s is checked by ``pick_place.holding_ok``)."""


class PlanExecutor:
    """The ``scripted-plan`` policy (see the module docstring).

    Attributes:
        trace: what happened in the episode, one line per operator, plan and recovery
            (``"<step> pick bowl_1 plate_1: ok"``), for diagnosis.
    """

    name = "scripted-plan"

    def __init__(self, planner: str = "auto") -> None:
        self.planner = planner

    def start(
        self, problem: LiberoProblem, robot: RobotDescription, scene: Scene,
        percept: LiberoPercept,
    ) -> None:  # fmt: skip
        """Plan the goal from the first percept."""
        self.drivers = {
            fixture: JointTargetDriver(
                robot, IKConfig(dt=1.0 / robot.control_hz, posture_cost=cost)
            )  # fmt: skip
            for fixture, cost in ((False, POSTURE_COST), (True, FIXTURE_POSTURE_COST))
        }
        driver = self.drivers[False]
        self.ctx = Context.at_start(scene, driver, robot, percept, problem)
        self.problem = problem
        self.trace: list[str] = []
        self.step, self.replans = 0, 0
        self.holding: str | None = None
        self.out_of_hand = 0  # steps the carried object has been perceived out of the hand
        self.runner: Runner | None = None
        self.current: tuple[str, tuple[str, ...]] | None = None
        self.queue: list[tuple[str, tuple[str, ...]]] = []
        self.seen: dict[str, np.ndarray] | None = _positions(percept)  # None: at rest
        self._plan(percept)

    def _plan(self, percept: LiberoPercept) -> None:
        """Plan from the perceived state (the hand at home and empty)."""
        perceived = replace(self.problem, init=perceived_init(self.problem, self.ctx.scene,
                                                              percept))  # fmt: skip
        result = plan_task(perceived, self.planner, SearchLimits(time_s=PLAN_TIME_S))
        steps = [s.action.split() for s in result.steps or ()]
        self.queue = [(s[0], tuple(s[1:])) for s in steps]
        grasps = doorway_grasps(self.ctx, self.queue)  # chosen for where it goes
        if not any(self._learned(op) for op in PICKS):  # not in its data
            reordered = pinched_last(self.ctx, self.queue)
            if reordered != self.queue and plan_holds(perceived, reordered):
                self.queue = reordered
            grasps = edge_grasps(self.ctx, self.queue) | grasps
            grasps |= neck_grasps(self.ctx, self.queue)
        self.ctx.grasps = grasps
        self.ctx.tipped = tipped(self.ctx, percept, self.queue)
        self.ctx.opening = frozenset(  # the approach turns the hand for the pull
            args[0] for (op, args), (then, on) in zip(self.queue, self.queue[1:], strict=False)
            if op == "approach" and then == "open" and on[0] == args[0]
        )  # fmt: skip
        self.trace.append(f"{self.step} plan ({result.status}): {len(self.queue)} steps")

    def _effect_holds(self, percept: LiberoPercept) -> bool:
        assert self.current is not None
        operator, args = self.current
        if operator in PICKS:
            return holding_ok(self.ctx, percept, args[0], self.start_z)
        if operator in CARRIES and self.holding is not None:
            return held(self.ctx.scene, percept, self.holding)
        if operator in EFFECTS:
            predicate, arity = EFFECTS[operator]
            return holds(self.ctx.scene, percept, Atom(predicate, args[:arity]))
        return True

    def _next(self, percept: LiberoPercept) -> bool:
        """Start the next operator (replanning when the plan is spent and the goal is not
        perceived); False when there is nothing left to run."""
        if not self.queue:
            if all(holds(self.ctx.scene, percept, a) for a in self.problem.goal):
                return False
            if self.replans >= MAX_REPLANS:
                return False
            self.replans += 1
            self._plan(percept)
            if not self.queue:
                return False
        self.current = self.queue.pop(0)
        operator, args = self.current
        at_fixture = self.holding is None and args[0] in self.ctx.scene.articulated
        fixture = operator in FIXTURE_OPERATORS or (operator == "approach" and at_fixture)
        self.ctx.driver = self.drivers[fixture]
        try:
            legs = operator_legs(self.ctx, operator, args, self.holding)
        except KeyError as err:
            self.trace.append(f"{self.step} {operator} {' '.join(args)}: {err}")
            self.queue.clear()
            self.replans = MAX_REPLANS
            self.current = None
            return False
        self.start_z = float(percept.position(args[0])[2]) if args[0] in percept.objects else 0.0
        self.runner = self._runner(operator, args, legs)
        return True

    def _learned(self, operator: str) -> bool:
        """Whether a learned skill runs ``operator`` (none here: ``skills.SkillsExecutor``).
        The learned pick was recorded on the scripted grasps before ``tall``'s neck grasp
        and is not given it: on LIBERO-Goal task 9 states 0-2 it won 0 / 3 with it, 2 / 3
        without."""
        return False

    def _runner(self, operator: str, args: tuple[str, ...], legs: list[Leg]) -> Runner:
        """What runs an operator: its scripted controller's legs (a policy with learned
        skills runs some operators otherwise: ``skills.SkillsExecutor``)."""
        return LegRunner(legs, self.ctx)

    def act(self, percept: LiberoPercept) -> np.ndarray:
        """The next action: the running operator's, or the next one's; held still when
        the plan is done or no plan is left."""
        self.step += 1
        if self.seen is not None:  # the scene settling (seen from one step on): hold still
            seen, self.seen = self.seen, _positions(percept)
            moved = max((float(np.linalg.norm(p - seen[o])) for o, p in self.seen.items()),
                        default=0.0)  # fmt: skip
            if (self.step == 1 or moved > SETTLED) and self.step <= SETTLE_STEPS:
                return np.r_[np.zeros(7), GRIPPER_OPEN]
            self.seen = None
            self.trace.append(f"{self.step} at rest")
        for _ in range(len(self.queue) + MAX_REPLANS + 3):
            if self.runner is None and not self._next(percept):
                break
            assert self.runner is not None
            if self._dropped(percept):  # the carry fails at once: its effect does not hold
                self._finish(percept)
                continue
            action = self.runner.act(percept)
            if action is not None:
                return action
            self._finish(percept)
        return np.r_[np.zeros(7), GRIPPER_OPEN]

    def _dropped(self, percept: LiberoPercept) -> bool:
        """Whether the object an ``approach`` or ``retreat`` carries has been perceived out
        of the hand for ``DROPPED_STEPS`` steps in a row."""
        carrying = self.current is not None and self.current[0] in CARRIES
        if not carrying or self.holding is None or held(self.ctx.scene, percept, self.holding):
            self.out_of_hand = 0
            return False
        self.out_of_hand += 1
        return self.out_of_hand >= DROPPED_STEPS

    def _finish(self, percept: LiberoPercept) -> None:
        """An operator's (or a recovery's) legs are done: check its effect; on failure
        let go and lift, then replan."""
        self.runner = None
        if self.current is None:  # a recovery ended: replan from what is perceived
            self.holding = None
            self.queue.clear()
            return
        operator, args = self.current
        ok = self._effect_holds(percept)
        self.trace.append(f"{self.step} {operator} {' '.join(args)}: {'ok' if ok else 'FAILED'}")
        if ok:
            if operator in PICKS:
                self.holding = args[0]
            elif operator in PLACES:
                self.holding = None
            return
        dropped = self.holding if operator in CARRIES else None
        if operator in PICKS or dropped is not None:  # the retry grasps otherwise
            obj = args[0] if dropped is None else dropped
            self.ctx.failures[obj] = self.ctx.failures.get(obj, 0) + 1
            self.holding = None
        self.current = None
        self.runner = LegRunner([hold(GRIPPER_OPEN, 8), up(0.10, GRIPPER_OPEN)], self.ctx)


def _positions(percept: LiberoPercept) -> dict[str, np.ndarray]:
    """Each movable object's perceived position."""
    return {obj: percept.position(obj) for obj in percept.objects}
