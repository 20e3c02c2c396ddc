"""The ``osg`` command: one sub-command per verb, each in ``osg_control.commands``.

Only the module of the verb being run is imported (the others are listed by name and help
from ``VERBS``), so ``osg --help`` and ``osg plan`` start without torch, MuJoCo or the
collector; ``tools/bench_startup.py`` measures it.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import sys
from collections.abc import Collection, Iterator, Sequence
from types import ModuleType

from osg_control import __version__
from osg_control.commands import (
    COMMAND_MODULES,
    DEFAULT_DOMAIN,
    domain_verb_names,
    domain_verbs,
)
from osg_control.commands.checks import check_args
from osg_control.commands.errors import handle_errors
from osg_control.errors import OSGError, UsageError, lookup

VERBS: tuple[tuple[str, str, str], ...] = (
    ("collect", "collect", "record scripted noisy episodes (Algorithm 1), one HDF5 file per skill"),
    ("datasets", "collect", "inspect data set files"),
    ("run", "run", "execute a task: classify, plan, run skills"),
    ("eval-skills", "run", "Table I: learned skills under noise"),
    ("evaluate", "evaluate", "full-pipeline evaluations"),
    ("classifier", "classifier", "state->skill classifier: train, eval, reach"),
    ("train", "train", "learn skills from their offline data sets (TD3+BC)"),
    ("graph", "graph", "build the skill graph, check it against data, save or draw it"),
    ("pddl", "pddl", "export the skill graph as PDDL"),
    ("plan", "plan", "plan a skill sequence for a goal"),
    ("reproduce", "reproduce", "run the whole pipeline and write a report"),
    ("domains", "domains", "list the registered domains (skills, facts, tasks, start regions)"),
    ("robots", "robots", "list the registered robots (joints, limits, TCP, gripper)"),
)
"""Every verb: its name, the ``osg_control.commands`` module that registers it, its help
(a test checks these against the modules), in ``COMMAND_MODULES`` order."""


def build_parser(
    modules: Collection[str] | None = None, own_verbs: ModuleType | None = None
) -> argparse.ArgumentParser:
    """Assemble the parser.

    Args:
        modules: the command modules to import and register in full; the verbs of the
            others get a bare parser with their help (enough to list them). None: all.
        own_verbs: the verbs module of a domain that brings its own (``domain_verbs``):
            its verbs replace the core's.
    """
    parser = argparse.ArgumentParser(
        prog="osg",
        description="Offline Skill Graph robot control: collect, train, plan, run.",
    )
    parser.add_argument("--version", action="version", version=f"osg-control {__version__}")
    parser.add_argument(
        "--domain",
        default=DEFAULT_DOMAIN,
        help=f"the domain to work in (default: {DEFAULT_DOMAIN}; `osg domains` lists them)",
    )
    parser.add_argument(
        "--robot",
        default=None,
        help="the robot the domain's env drives (default: the domain's own; `osg robots` "
        "lists them)",
    )
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    if own_verbs is not None:
        own_verbs.register(subparsers)
        return parser
    for module_name in COMMAND_MODULES:
        if modules is None or module_name in modules:
            importlib.import_module(f"osg_control.commands.{module_name}").register(subparsers)
        else:
            for verb, module, help_text in VERBS:
                if module == module_name:
                    subparsers.add_parser(verb, help=help_text)
    return parser


GLOBAL_OPTIONS_WITH_VALUE = ("--domain", "--robot")
"""Options before the verb that take a value (the value is not the verb)."""


def _modules_for(argv: Sequence[str]) -> list[str]:
    """The command module of the verb in ``argv`` (the first word that is neither an option
    nor an option's value), if any."""
    verb = None
    words = iter(argv)
    for word in words:
        if word in GLOBAL_OPTIONS_WITH_VALUE:
            next(words, None)
        elif not word.startswith("-"):
            verb = word
            break
    return [module for name, module, _ in VERBS if name == verb]


def _domain_in(argv: Sequence[str]) -> str:
    """The ``--domain`` value of ``argv`` (either form; the last one wins), else the
    default."""
    name = DEFAULT_DOMAIN
    for k, word in enumerate(argv):
        if word == "--domain" and k + 1 < len(argv):
            name = argv[k + 1]
        elif word.startswith("--domain="):
            name = word.split("=", 1)[1]
    return name


def hoist_global_options(argv: Sequence[str]) -> list[str]:
    """``argv`` with ``--domain NAME`` and ``--robot NAME`` (or ``--domain=NAME``, ...) moved
    before the verb, so that
    ``osg reproduce --domain franka-kitchen`` means ``osg --domain franka-kitchen
    reproduce``."""
    words, hoisted = list(argv), []
    k = 0
    while k < len(words):
        word = words[k]
        if word in GLOBAL_OPTIONS_WITH_VALUE and k + 1 < len(words):
            hoisted += words[k : k + 2]
            del words[k : k + 2]
        elif word.split("=", 1)[0] in GLOBAL_OPTIONS_WITH_VALUE:
            hoisted.append(words.pop(k))
        else:
            k += 1
    return hoisted + words


def check_domain_name(name: str) -> None:
    """``--domain`` (either form, any verb, ``domains`` too) names a known domain, maybe
    with object counts (``kitchen[cube=2]``, ``Domain.with_counts``) it can build.

    Raises:
        UsageError: naming the option, the value and the known domains, or why the
            counts are refused.
    """
    from osg_control.domain.registry import domain_names, get_domain

    known = dict.fromkeys(sorted({*domain_names(), *domain_verb_names()}))
    lookup(known, name.split("[", 1)[0], "domain", lambda m: UsageError(f"--domain: {m}"))
    if "[" in name:
        try:
            get_domain(name)
        except OSGError as err:
            raise UsageError(f"--domain: {err}") from None


def check_robot_name(name: str | None) -> None:
    """``--robot`` (any verb) names a registered robot.

    Raises:
        UsageError: naming the option, the value and the known robots.
    """
    if name is None:
        return
    from osg_control.robots.registry import robot_names

    lookup(dict.fromkeys(robot_names()), name, "robot", lambda m: UsageError(f"--robot: {m}"))


@contextlib.contextmanager
def selected_robot(args: argparse.Namespace) -> Iterator[None]:
    """Run the command with ``--robot``'s robot in the domain (``Domain.with_robot``): every
    ``get_domain`` of the domain gives it while the command runs, in forked workers too."""
    if args.robot is None or args.command in ("domains", "robots"):
        yield
        return
    from osg_control.domain.registry import domain_override, get_domain

    with domain_override(get_domain(args.domain).with_robot(args.robot), args.domain):
        yield


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the process exit code (``errors.EXIT_CODES``: 0 success, 1 an
    osg-control error, 2 a bad command-line value, 3 no plan, 4 no answer within the
    planner's limits, 5 malformed PDDL, 130 interrupted)."""
    argv = hoist_global_options(sys.argv[1:] if argv is None else argv)
    own_verbs = domain_verbs(_domain_in(argv))
    if own_verbs is None:
        parser = build_parser(_modules_for(argv))
    else:
        parser = build_parser(own_verbs=own_verbs)
    args = parser.parse_args(argv)
    with handle_errors(debug=args.debug or bool(os.environ.get("OSG_DEBUG"))) as outcome:
        if not getattr(args, "func", None):
            parser.print_help()
            return 0
        if own_verbs is None:
            check_domain_name(args.domain)
        elif args.robot is not None:
            raise UsageError(f"--robot: domain {args.domain!r} drives its own arm")
        check_robot_name(args.robot)
        check_args(args, domain_values=own_verbs is None)
        with selected_robot(args):
            outcome.code = int(args.func(args) or 0)
    return outcome.code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
