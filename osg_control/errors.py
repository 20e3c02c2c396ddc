"""One exception tree for the package, so callers can catch ``OSGError``."""

from collections.abc import Callable, Mapping
from typing import TypeVar

T = TypeVar("T")


class OSGError(Exception):
    """Base class of every error raised by osg-control."""


class ModelNotFoundError(OSGError, FileNotFoundError):
    """A robot or scene model file could not be found; the message names the paths searched."""


class ControllerError(OSGError):
    """The IK controller could not produce a command (bad input or solver failure)."""


class SimulationError(OSGError):
    """The physics diverged (MuJoCo warning or non-finite state)."""


class DatasetError(OSGError):
    """A data set file is missing, truncated or malformed; the message names the file."""


class CheckpointError(OSGError):
    """A checkpoint is missing, corrupt or does not match the environment."""


class SkillSpecError(OSGError):
    """A skill specification is invalid; the message names the skill and the field."""


class PDDLError(OSGError):
    """PDDL input is malformed or unsupported; the message names the file and line."""


class PlanningError(OSGError):
    """The planner cannot solve the task (e.g. unknown goal facts)."""


class BackendError(OSGError):
    """An executor backend is unknown, not installed or cannot reach its cluster."""


def lookup(table: Mapping[str, T], name: str, what: str, error: Callable[[str], Exception]) -> T:
    """``table[name]``; for an unknown name raise ``error`` naming it and the known ones
    (``unknown <what> 'x'; known <what>s: a, b``)."""
    try:
        return table[name]
    except KeyError:
        known = ", ".join(table)
        raise error(f"unknown {what} {name!r}; known {what}s: {known}") from None


class DomainError(OSGError):
    """A domain is malformed or unknown; the message names the domain and the field."""


class UsageError(OSGError):
    """A command-line value is out of its domain; the message names the option."""


class OutputError(OSGError):
    """A file or folder cannot be written (or read); the message names the path."""


class TrainingError(OSGError):
    """Training cannot go on (e.g. a non-finite loss); nothing is saved."""


EXIT_CODES: dict[str, int] = {
    "success": 0,
    "failure": 1,
    "usage": 2,
    "no plan": 3,
    "plan unknown": 4,
    "pddl input": 5,
    "interrupted": 130,
}
"""The ``osg`` exit codes: 0 success; 1 an osg-control error (bad file, diverged physics, a
failed episode); 2 a bad command-line value; 3 the planner proved the goal unreachable;
4 ``osg plan`` hit a time or state limit (no answer); 5 ``osg plan`` was handed malformed
or unsupported PDDL; 130 interrupted (Ctrl-C or SIGTERM)."""


class EnvOptionError(OSGError, ValueError):
    """An env reset option or configuration field is unknown, non-finite, out of range or
    contradictory; the message names it."""


class PlacementError(EnvOptionError):
    """Objects cannot be placed where asked: more than their region fits, or two explicit
    placements overlapping; the message names them."""
