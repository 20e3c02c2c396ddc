"""The ``osg`` top-level error handler: every error becomes one line on stderr and an exit
code (``errors.EXIT_CODES``); ``--debug`` (or ``OSG_DEBUG=1``) adds the traceback.

SIGTERM is handled like Ctrl-C in the main process: the work in progress stops the same
way (finished chunks kept, exit 130); both are also marked (``lazy.INTERRUPTED``), so
that one swallowed by a finalizer still ends a long job at its next result. A closed
standard output (``osg ... | head``) ends the command quietly, as POSIX tools do: no
message, exit 1 (the Python docs' recipe for SIGPIPE).
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
import sys
import threading
import traceback
from collections.abc import Iterator
from dataclasses import dataclass
from types import FrameType

from osg_control.errors import EXIT_CODES, OSGError, UsageError
from osg_control.parallel.lazy import INTERRUPTED


@dataclass
class Outcome:
    """The exit code the command (or the handler) settled on."""

    code: int = 0


def _interrupts(main_pid: int) -> None:
    """Raise ``KeyboardInterrupt`` on Ctrl-C and SIGTERM in this process, and mark it
    (``lazy.INTERRUPTED``: a long job raises it again should a finalizer swallow it);
    children keep the default."""

    def handler(signum: int, _frame: FrameType | None) -> None:
        if os.getpid() != main_pid:
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)
            return
        INTERRUPTED.set()
        raise KeyboardInterrupt

    signal.signal(signal.SIGINT, handler)
    signal.signal(signal.SIGTERM, handler)


def _stdout_closed() -> bool:
    """Whether standard output is a pipe whose reader has gone (then silence it: point it at
    /dev/null, so that flushing it at exit raises nothing)."""
    try:
        descriptor = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # replaced by a non-file (a test's capture)
        return False
    poller = select.poll()
    poller.register(descriptor, 0)  # a pipe's write end reports POLLERR once its reader closed
    if not any(events & select.POLLERR for _fd, events in poller.poll(0)):
        return False
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, descriptor)
    os.close(devnull)
    return True


def _report(message: str, debug: bool) -> None:
    if debug:
        traceback.print_exc()
    print(f"osg: error: {message}", file=sys.stderr)


@contextlib.contextmanager
def handle_errors(debug: bool = False) -> Iterator[Outcome]:
    """Run a command's body; map its exceptions to a message and ``Outcome.code``."""
    outcome = Outcome()
    in_main_thread = threading.current_thread() is threading.main_thread()
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    INTERRUPTED.clear()
    if in_main_thread:  # signal handlers can only be set there
        _interrupts(os.getpid())
    try:
        yield outcome
        sys.stdout.flush()  # a closed pipe shows here, not as a warning at exit
    except BrokenPipeError as err:
        if not _stdout_closed():
            _report(f"broken pipe: {err}", debug)
        outcome.code = EXIT_CODES["failure"]
    except UsageError as err:
        _report(str(err), debug)
        outcome.code = EXIT_CODES["usage"]
    except OSGError as err:
        _report(str(err), debug)
        outcome.code = EXIT_CODES["failure"]
    except KeyboardInterrupt:
        if debug:
            traceback.print_exc()
        print("osg: interrupted", file=sys.stderr)
        outcome.code = EXIT_CODES["interrupted"]
    except OSError as err:
        _report(f"{err.filename or 'file system'}: {err.strerror or err}", debug)
        outcome.code = EXIT_CODES["failure"]
    except Exception as err:
        hint = "" if debug else "; rerun with osg --debug for the traceback"
        _report(f"internal error {type(err).__name__}: {err} (please report it){hint}", debug)
        outcome.code = EXIT_CODES["failure"]
    finally:
        INTERRUPTED.clear()  # a later job in this process (the Python API) runs on
        if in_main_thread:
            for sig, handler in previous.items():
                signal.signal(sig, handler)
