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
import threading
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


def partial_name(path: str | Path, keep_suffix: bool = False) -> Path:
    """The temporary name :func:`atomic_output` writes ``path`` under: ``<name>.partial``, or
    with ``keep_suffix`` ``.<stem>.partial<suffix>`` (hidden, and still ending in the suffix, for
    writers that pick the format by it: image encoders, ONNX checkers)."""
    path = Path(path)
    if keep_suffix and path.suffix:
        return path.with_name(f".{path.stem}.partial{path.suffix}")
    return path.with_name(path.name + ".partial")


@contextmanager
def atomic_output(path: str | Path, keep_suffix: bool = False) -> Iterator[Path]:
    """Yields the temporary path to write ``path``'s content to; renamed over ``path`` when the
    block ends normally, removed when it raises (a KeyboardInterrupt as well). The temporary
    name is :func:`partial_name`'s, in the same folder (so the rename is atomic)."""
    path = Path(path)
    tmp = partial_name(path, keep_suffix)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def copy_atomic(source: str | Path, path: str | Path) -> Path:
    """Copies ``source`` to ``path`` through :func:`atomic_output` (``source`` may lie on another
    file system, e.g. a temporary folder, where a plain rename would fail)."""
    import shutil

    path = Path(path)
    with atomic_output(path, keep_suffix=True) as tmp:
        shutil.copyfile(source, tmp)
    return path


def _nearest_existing(folder: Path, path: Path, option: str) -> Path:
    """The deepest of ``folder`` and its parents that exists (what ``mkdir -p`` would create the
    rest under); refused when that is not a folder or cannot be reached."""
    ancestor = folder
    while True:
        try:
            mode = os.stat(ancestor).st_mode
        except FileNotFoundError:
            if ancestor == ancestor.parent:
                raise InputError(path, f"{option}: no folder to create it in") from None
            ancestor = ancestor.parent
            continue
        except NotADirectoryError:  # a file on the way: a/file/b
            ancestor = ancestor.parent
            continue
        except OSError as exc:  # a name too long, a loop of links
            raise InputError(path, f"{option}: {ancestor}: {exc.strerror}") from None
        if not stat.S_ISDIR(mode):
            raise InputError(path, f"{option}: {ancestor} is not a folder")
        return ancestor


def _require_writable_folder(folder: Path, path: Path, option: str) -> None:
    """Creates and removes a probe file in ``folder``: ``os.access`` says yes to root even where
    nothing can be created (/proc, /sys, a read-only mount)."""
    probe = folder / f".slslam-probe-{os.getpid()}-{threading.get_ident()}"
    try:
        fd = os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as exc:
        raise InputError(
            path, f"{option}: the folder {folder} is not writable ({exc.strerror})"
        ) from None
    os.close(fd)
    os.unlink(probe)


def check_output_target(path: str | Path, option: str) -> Path:
    """An output file (written through :func:`atomic_output`): refused, before any work, when it
    names a folder or a FIFO, device or socket, when a file stands where a folder must be
    (``a/file/b.onnx``), or when the folder it goes in, or would be created under, cannot be
    written (tried with a probe file)."""
    path = Path(path)
    kind = special_file_kind(path)
    if kind not in (None, "missing"):
        raise InputError(path, f"{option} names {kind}; give a file name")
    if len(path.name.encode("utf-8", "surrogateescape")) > 255:
        raise InputError(path, f"{option}: the file name is longer than 255 bytes")
    parent = path.parent if str(path.parent) else Path(".")
    _require_writable_folder(_nearest_existing(parent, path, option), path, option)
    if kind is None and not os.access(path, os.W_OK):
        raise InputError(path, f"{option}: the file exists and is not writable")
    return path


def check_output_folder(path: str | Path, option: str) -> Path:
    """An output folder (created when missing): refused, before any work, when it names a file
    or a FIFO, device or socket, when a file stands on its way, or when it (or the folder it
    would be created under) cannot be written (tried with a probe file)."""
    path = Path(path)
    kind = special_file_kind(path)
    if kind is None:
        raise InputError(path, f"{option} names an existing file; give a folder (it is created)")
    if kind not in ("a folder", "missing"):
        if kind.startswith("not accessible"):
            raise InputError(path, f"{option}: {kind[len('not accessible ') :].strip('()')}")
        raise InputError(path, f"{option} names {kind}; give a folder (it is created)")
    for part in path.parts:
        if len(part.encode("utf-8", "surrogateescape")) > 255:
            raise InputError(path, f"{option}: a name in the path is longer than 255 bytes")
    _require_writable_folder(_nearest_existing(path, path, option), path, option)
    return path


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Writes ``text`` (UTF-8) to ``path`` through :func:`atomic_output`."""
    path = Path(path)
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path
