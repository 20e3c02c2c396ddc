"""The paper's five kitchen tasks: one list that the PDDL problems, the executor's
evaluations (Tables IV/V) and the report all read."""

from __future__ import annotations

from dataclasses import dataclass

from osg_control.errors import PlanningError, lookup
from osg_control.kitchen.skills import DOOR_OPENED

DEFAULT_WORLD: tuple[str, ...] = ("door-closed", "cube-on-counter", "hand-empty")
"""The kitchen's world facts at the start of a task: door shut, cube on the counter."""


@dataclass(frozen=True)
class KitchenTask:
    """One of the paper's kitchen tasks.

    Attributes:
        name: hyphenated (also the PDDL problem's name and file name).
        goal: the world facts to reach.
        world: the world facts at the start.
        node: the graph node the PDDL problem starts at (evaluations start anywhere).
        description: one line for humans.
    """

    name: str
    goal: tuple[str, ...]
    world: tuple[str, ...] = DEFAULT_WORLD
    node: str = "home"
    description: str = ""

    @property
    def door_opening(self) -> float:
        """Door travel [m] of the simulated start world."""
        return DOOR_OPENED if "door-open" in self.world else 0.0


KITCHEN_TASKS: tuple[KitchenTask, ...] = (
    KitchenTask("pick-up", ("cube-lifted",), description="pick the cube up"),
    KitchenTask(
        "open-door",
        ("door-open", "hand-empty"),
        description="slide the cabinet door open and let go of the handle",
    ),
    KitchenTask("open-pick-up", ("door-open", "cube-lifted"), description="open the door, pick up"),
    KitchenTask(
        "pick-up-place",
        ("cube-in-cabinet",),
        world=("door-open", "cube-on-counter", "hand-empty"),
        description="door already open: pick the cube up and place it in the cabinet",
    ),
    KitchenTask(
        "open-pick-up-place",
        ("door-open", "cube-in-cabinet"),
        description="open the door, pick the cube up, place it in the cabinet",
    ),
)
"""The paper's five long-horizon tasks (Tables IV and V), in its order."""
TASKS_BY_NAME: dict[str, KitchenTask] = {task.name: task for task in KITCHEN_TASKS}


def get_task(name: str) -> KitchenTask:
    """Look a task up by name.

    Raises:
        PlanningError: for an unknown name, listing the known ones.
    """
    return lookup(TASKS_BY_NAME, name, "task", PlanningError)
