"""Sub-commands of ``osg``; each module defines ``register(subparsers)``.

A module's ``register`` adds its parser and sets ``func`` (called with the parsed args,
returning the exit code). Add a module here to expose it.
"""

COMMAND_MODULES: tuple[str, ...] = (
    "collect",
    "run",
    "evaluate",
    "classifier",
    "train",
    "graph",
    "pddl",
    "plan",
    "reproduce",
)
