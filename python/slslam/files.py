"""Input files checked before they are opened, and output files written whole or not at all.

- :func:`require_regular_file`: a path that is missing, a folder, a FIFO, a socket or a device
  (``/dev/zero``, a named pipe that would block ``open()`` until a writer comes) is refused with
  one line naming it, before any byte is read;
- :func:`atomic_output`: a file is written under ``<name>.partial`` and renamed over ``name``
  only when complete, so an interrupted or failed write never leaves a truncated file under the
  final name (and the ``.partial`` is removed).
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from slslam.errors import InputError


def special_file_kind(path: Path) -> str | None:
    """What ``path`` is when it is not a regular file ("a folder", "a FIFO", ...); None for a
    regular file. A missing path is "missing". Symbolic links are followed."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return "missing"
    except OSError as exc:  # a loop of links, a name too long, no permission on a parent
        return f"not accessible ({exc.strerror})"
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def require_regular_file(
    path: str | Path, error: type[InputError] = InputError, what: str = "file"
) -> Path:
    """``path`` as a Path when it is a readable regular file; else ``error(path, ...)`` saying
    what it is instead (checked with ``stat``: a FIFO or device is never opened)."""
    path = Path(path)
    kind = special_file_kind(path)
    if kind == "missing":
        raise error(path, f"{what} not found")
    if kind is not None:
        raise error(path, f"is {kind}, not a {what}" if kind[0] == "a" else f"{what} {kind}")
    return path


def check_output_file(path: str | Path, option: str) -> Path:
    """An output file named by ``option``: refused when it names a folder or something not a
    regular file, or when its folder exists but cannot be written (checked before a run starts,
    not when the run ends)."""
    path = Path(path)
    kind = special_file_kind(path)
    if kind not in (None, "missing"):
        raise InputError(path, f"{option} names {kind}; give a file name")
    parent = path.parent if str(path.parent) else Path(".")
    if parent.exists():
        if not parent.is_dir():
            raise InputError(path, f"{option}: {parent} is not a folder")
        if not os.access(parent, os.W_OK | os.X_OK):
            raise InputError(path, f"{option}: the folder {parent} is not writable")
    if kind is None and not os.access(path, os.W_OK):
        raise InputError(path, f"{option}: the file exists and is not writable")
    return path


@contextmanager
def atomic_output(path: str | Path) -> Iterator[Path]:
    """Yields the temporary path to write ``path``'s content to; renamed over ``path`` when the
    block ends normally, removed when it raises (a KeyboardInterrupt as well)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".partial")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Writes ``text`` (UTF-8) to ``path`` through :func:`atomic_output`."""
    path = Path(path)
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path
