"""Plan a LIBERO task: its task file's goal over the lifted domain ``osg-libero``."""

from __future__ import annotations

from osg_control.errors import PlanningError
from osg_control.libero.operators import libero_domain
from osg_control.libero.pddl_export import check_goals, to_pddl
from osg_control.libero.problem import LiberoProblem
from osg_control.planning.api import solve
from osg_control.planning.grounding import ground
from osg_control.planning.task import NO_LIMITS, PlanResult, SearchLimits


def plan_task(
    problem: LiberoProblem, planner: str = "auto", limits: SearchLimits = NO_LIMITS
) -> PlanResult:
    """The cheapest plan for the task's goal from its init (``planning.api.solve``).

    Raises:
        UnsupportedPredicateError: a goal predicate no operator achieves (named, with the
            operators that exist), before anything is grounded.
        PlanningError: an unknown planner, or the backend failed.
    """
    check_goals([problem])
    domain = libero_domain([problem])
    return solve(domain, to_pddl(problem, domain), planner, limits=limits)


def plan_holds(problem: LiberoProblem, steps: list[tuple[str, tuple[str, ...]]]) -> bool:
    """Whether ``steps`` (operator, arguments), applied in order from the task's init, are
    each applicable and reach its goal (a plan the executor reordered)."""
    domain = libero_domain([problem])
    task = ground(domain, to_pddl(problem, domain))
    try:
        return task.is_goal(task.simulate(" ".join([op, *args]) for op, args in steps))
    except PlanningError:
        return False
