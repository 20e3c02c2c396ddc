"""The kitchen's tasks: the paper's five, the valve's two, and two with two cubes; one
list that the PDDL problems, the executor's evaluations (Tables IV/V) and the report all
read."""

from __future__ import annotations

from osg_control.domain.base import Task
from osg_control.errors import PlanningError, lookup

DEFAULT_WORLD: tuple[str, ...] = ("door-closed", "cube-on-counter", "hand-empty", "valve-closed")
"""The kitchen's world facts at the start of a task: door shut, cube on the counter, valve
shut."""


TWO_CUBES: tuple[tuple[str, int], ...] = (("cube", 2),)
"""The object counts of a task with two cubes (``Task.counts``)."""
TWO_CUBE_WORLD: tuple[str, ...] = (*DEFAULT_WORLD, "(on-counter cube-2)")
"""The start of a two-cube task: both cubes on the counter."""


def _task(
    name: str,
    goal: tuple[str, ...],
    world: tuple[str, ...] = DEFAULT_WORLD,
    description: str = "",
    counts: tuple[tuple[str, int], ...] = (),
) -> Task:
    return Task(name, goal, world, "home", description, counts)


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
    _task(
        "two-cubes-in-cabinet",
        ("door-open", "cube-in-cabinet", "(in-cabinet cube-2)"),
        world=TWO_CUBE_WORLD,
        description="two cubes: open the door, put both cubes in the cabinet",
        counts=TWO_CUBES,
    ),
    _task(
        "pick-up-cube-2",
        ("(lifted cube-2)",),
        world=TWO_CUBE_WORLD,
        description="two cubes: pick up the second (blue) one",
        counts=TWO_CUBES,
    ),
)
"""The paper's five long-horizon tasks (Tables IV and V), in its order, then the tasks the
valve's skills added to the graph, then the tasks of a scene with two cubes."""
TASKS_BY_NAME: dict[str, Task] = {task.name: task for task in KITCHEN_TASKS}


def get_task(name: str) -> Task:
    """Look a task up by name.

    Raises:
        PlanningError: for an unknown name, listing the known ones.
    """
    return lookup(TASKS_BY_NAME, name, "task", PlanningError)
