"""Safe file output: atomic writes with the umask's mode, and output checks before long work.

Every writer of the package goes through ``atomic_write`` (a temporary file in the target's
folder, renamed over it), so an interrupted write leaves the old file or none, and a
file-system error surfaces as an ``OutputError`` naming the path instead of an ``OSError``.
Commands that compute for minutes call ``check_output_dir`` first, so an unwritable
destination is refused before the work rather than after it.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

from osg_control.errors import OutputError
from osg_control.paths import PACKAGE_DIR

__all__ = [
    "atomic_folder",
    "atomic_write",
    "check_output_dir",
    "file_mode",
    "output_errors",
    "refuse_package",
]


def file_mode() -> int:
    """The mode a plain ``open(path, "w")`` would give a new file (0o666 minus the umask)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


@contextlib.contextmanager
def output_errors(path: Path, action: str = "cannot write") -> Iterator[None]:
    """Turn an ``OSError`` raised inside the block into an ``OutputError`` naming ``path``."""
    try:
        yield
    except OSError as err:
        reason = err.strerror or str(err)
        raise OutputError(f"{path}: {action} ({reason})") from err


def refuse_package(path: Path) -> None:
    """Refuse a destination inside the installed package (its shipped defaults stay intact).

    Raises:
        OutputError: ``path`` lies under ``PACKAGE_DIR``.
    """
    resolved = Path(path).expanduser().resolve()
    if resolved == PACKAGE_DIR or PACKAGE_DIR in resolved.parents:
        raise OutputError(
            f"{path}: inside the installed package {PACKAGE_DIR}; write trained artifacts to "
            "the cache ($OSG_CACHE_DIR) or an --out folder outside it"
        )


def atomic_write(path: str | Path, write: Callable[[Path], object]) -> Path:
    """Create ``path`` by calling ``write(tmp)`` on a temporary sibling, then renaming it.

    The file gets the umask's mode (``file_mode``), not ``mkstemp``'s 0600; the folder is
    created if missing. The temporary name ends in ``path``'s suffix, so writers that pick
    their format from the extension (matplotlib, imageio) write the right one.

    Raises:
        OutputError: the folder or file cannot be written, or lies inside the package
            (``refuse_package``); names the path.
    """
    path = Path(path)
    refuse_package(path)
    with output_errors(path):
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(
            prefix=f".{path.name}.", suffix=f".tmp{path.suffix}", dir=path.parent
        )
        os.close(fd)
    tmp = Path(name)
    try:
        with output_errors(path):
            write(tmp)
            os.chmod(tmp, file_mode())
            os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def atomic_folder(target: Path, fill: Callable[[Path], object]) -> Path:
    """Create folder ``target`` by calling ``fill(staging)`` on a new sibling folder, then
    moving it in place; an old ``target`` is set aside first and removed only once the new
    one is there, so a failure at any point keeps one of them, whole.

    Raises:
        OutputError: the folder cannot be written, or lies inside the package; names it.
    """
    refuse_package(target)
    with output_errors(target):
        target.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
    try:
        with output_errors(target):
            fill(staging)
            if not target.exists():
                staging.rename(target)
                return target
            old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old.", dir=target.parent))
            old.rmdir()
            target.rename(old)
            try:
                staging.rename(target)
            except OSError:
                old.rename(target)
                raise
            shutil.rmtree(old, ignore_errors=True)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return target


MIN_FREE_BYTES = 16 * 2**20
"""Free space a long job's output folder must have when its output size is not known."""


def check_output_dir(
    path: str | Path, what: str = "output folder", min_free: int = MIN_FREE_BYTES
) -> Path:
    """Make sure files can be created in folder ``path`` (creating it) and that it has
    ``min_free`` bytes free, before long work.

    Raises:
        OutputError: the folder cannot be created or written, is a file, or has less than
            ``min_free`` bytes free; names the path.
    """
    path = Path(path).expanduser()
    refuse_package(path)
    if path.exists() and not path.is_dir():
        raise OutputError(f"{path}: {what} is not a folder")
    with output_errors(path, f"cannot write the {what}"):
        path.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(prefix=".osg-write-check.", dir=path)
        os.close(fd)
        os.unlink(name)
        free = shutil.disk_usage(path).free
    if free < min_free:
        raise OutputError(
            f"{path}: not enough free space for the {what} "
            f"({free / 2**20:.1f} MiB free, {min_free / 2**20:.1f} MiB needed)"
        )
    return path
