"""Robots by name: the package's own (those built from an optional dependency's files only
where it is installed: ``OPTIONAL``), those announced by installed packages, and those
registered in process.

A package announces a robot with an entry point in the ``osg_control.robots`` group whose
object is a ``RobotDescription`` or a zero-argument function returning one;
``register_robot`` adds one at run time (e.g. from a test or a notebook). A robot is
checked against its models (``robot_model.check_models``) the first time it is asked for,
then cached.
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable
from functools import partial
from importlib.metadata import entry_points
from typing import Any

from osg_control.control.description import RobotDescription, RobotDescriptionError
from osg_control.control.robot_model import check_models
from osg_control.errors import ModelNotFoundError

ENTRY_POINT_GROUP = "osg_control.robots"
BUILTIN: dict[str, str] = {
    "panda": "osg_control.robots.panda:PANDA",
    "ur5": "osg_control.robots.ur5:ur5_description",
}
"""The robots this package ships: name -> ``module:attribute``."""
OPTIONAL: dict[str, tuple[str, str, str]] = {
    "franka-kitchen-panda": (
        "osg_control.robots.franka_kitchen_panda:kitchen_panda_description",
        "gymnasium_robotics",
        "franka",
    ),
}
"""Robots this package ships whose models come from an optional dependency: name ->
(``module:attribute``, the package its models need, the extra that installs it). Listed
only where that package is installed."""

_REGISTERED: dict[str, Callable[[], RobotDescription]] = {}
_LOADED: dict[str, RobotDescription] = {}


def register_robot(robot: RobotDescription | Callable[[], RobotDescription]) -> None:
    """Make a robot available under its name (replacing one of the same name); a factory
    is registered under the name of what it builds."""
    built = robot if isinstance(robot, RobotDescription) else robot()
    _REGISTERED[built.name] = lambda: built
    _LOADED.pop(built.name, None)


def _load(reference: str) -> Any:
    module, _, attribute = reference.partition(":")
    return getattr(importlib.import_module(module), attribute)


def _sources() -> dict[str, Callable[[], Any]]:
    """Name -> a loader of its description (or of a factory giving one)."""
    sources: dict[str, Callable[[], Any]] = {
        name: partial(_load, ref) for name, ref in BUILTIN.items()
    }
    sources.update(
        {
            name: partial(_load, ref)
            for name, (ref, package, _extra) in OPTIONAL.items()
            if _installed(package)
        }
    )
    sources.update({point.name: point.load for point in entry_points(group=ENTRY_POINT_GROUP)})
    sources.update(_REGISTERED)
    return sources


def _installed(package: str) -> bool:
    return importlib.util.find_spec(package) is not None


def robot_names() -> list[str]:
    """Every known robot name, sorted."""
    return sorted(_sources())


def get_robot(name: str) -> RobotDescription:
    """The robot registered under ``name``, checked against its models.

    Raises:
        RobotDescriptionError: an unknown name (the known ones listed), or a description
            that does not match its models (named).
        ModelNotFoundError: a model file the robot needs is not installed (an optional
            robot's package missing: the extra to install named).
    """
    if name in _LOADED:
        return _LOADED[name]
    source = _sources().get(name)
    if source is None and name in OPTIONAL:
        _ref, package, extra = OPTIONAL[name]
        raise ModelNotFoundError(
            f"robot {name!r} is built from {package}'s files, which is not installed: "
            f"pip install 'osg-control[{extra}]'"
        )
    if source is None:
        raise RobotDescriptionError(
            f"unknown robot {name!r}; known robots: {', '.join(robot_names())}"
        )
    robot = source()
    if not isinstance(robot, RobotDescription):
        robot = robot()
    if not isinstance(robot, RobotDescription):
        raise RobotDescriptionError(f"robot {name!r}: its source gave {type(robot).__name__}")
    if robot.name != name:
        raise RobotDescriptionError(f"robot {name!r}: its description is named {robot.name!r}")
    check_models(robot)
    _LOADED[name] = robot
    return robot
