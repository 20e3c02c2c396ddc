"""The paper's five kitchen tasks: one list that the PDDL problems, the executor's
evaluations (Tables IV/V) and the report all read."""

from __future__ import annotations

from osg_control.domain.base import Task
from osg_control.errors import PlanningError, lookup

DEFAULT_WORLD: tuple[str, ...] = ("door-closed", "cube-on-counter", "hand-empty", "valve-closed")
"""The kitchen's world facts at the start of a task: door shut, cube on the counter, valve
shut."""


def _task(
    name: str,
    goal: tuple[str, ...],
    world: tuple[str, ...] = DEFAULT_WORLD,
    description: str = "",
) -> Task:
    return Task(name, goal, world, "home", description)


KITCHEN_TASKS: tuple[Task, ...] = (
    _task("pick-up", ("cube-lifted",), description="pick the cube up"),
    _task(
        "open-door",
        ("door-open", "hand-empty"),
        description="slide the cabinet door open and let go of the handle",
    ),
    _task("open-pick-up", ("door-open", "cube-lifted"), description="open the door, pick up"),
    _task(
        "pick-up-place",
        ("cube-in-cabinet",),
        world=("door-open", "cube-on-counter", "hand-empty", "valve-closed"),
        description="door already open: pick the cube up and place it in the cabinet",
    ),
    _task(
        "open-pick-up-place",
        ("door-open", "cube-in-cabinet"),
        description="open the door, pick the cube up, place it in the cabinet",
    ),
    _task(
        "turn-valve",
        ("valve-open", "hand-empty"),
        description="push the valve's lever round by about 1 rad (nothing is grasped)",
    ),
    _task(
        "open-door-turn-valve",
        ("door-open", "valve-open", "hand-empty"),
        description="slide the cabinet door open, let go of the handle, turn the valve",
    ),
)
"""The paper's five long-horizon tasks (Tables IV and V), in its order, then the tasks the
valve's skills added to the graph."""
TASKS_BY_NAME: dict[str, Task] = {task.name: task for task in KITCHEN_TASKS}


def get_task(name: str) -> Task:
    """Look a task up by name.

    Raises:
        PlanningError: for an unknown name, listing the known ones.
    """
    return lookup(TASKS_BY_NAME, name, "task", PlanningError)
