"""Content keys of benchmark cells: a cell is re-run only when its key changes.

A key is the SHA-256 of the canonical JSON (sorted keys, no whitespace) of everything that
decides a cell's result: the sequence (simulator options after their defaults, or a recorded
sequence's path and file listing), the configuration after defaults (the complete config a run
uses, or the LiDAR options), the seed, the slslam version and the C++ core build (its version,
commit and the SHA-256 of the compiled module).
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
from pathlib import Path
from typing import Any

#: Bumped when the cell record's layout or the meaning of a key field changes.
KEY_SCHEMA = 1


def canonical_json(value: Any) -> str:
    """``value`` as JSON with sorted keys and no whitespace: equal content, equal text."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=True, default=str)


def digest(value: Any) -> str:
    """SHA-256 (hex) of :func:`canonical_json` of ``value``."""
    return hashlib.sha256(canonical_json(value).encode("utf-8")).hexdigest()


def file_sha256(path: str | Path, chunk: int = 1 << 20) -> str:
    h = hashlib.sha256()
    with Path(path).open("rb") as f:
        while block := f.read(chunk):
            h.update(block)
    return h.hexdigest()


@functools.cache
def core_build() -> dict[str, str]:
    """The C++ core this process loads: version, commit and the module file's SHA-256 (a rebuild
    from the same commit with other flags is another build)."""
    from slslam import _core

    module = getattr(_core, "__file__", None)
    return {
        "version": str(getattr(_core, "__version__", "unknown")),
        "commit": str(getattr(_core, "__git_commit__", "unknown")),
        "module_sha256": file_sha256(module) if module and Path(module).is_file() else "unknown",
    }


def software() -> dict[str, Any]:
    """slslam's version and the core build: part of every cell key."""
    from slslam._version import __version__

    return {"slslam": __version__, "core": core_build()}


def tree_fingerprint(path: Path) -> dict[str, Any]:
    """A recorded sequence's identity without reading its data: the path, and the number, total
    size [bytes] and latest modification time [ns] of its files (a file replaced or added
    changes it)."""
    path = Path(path)
    if path.is_file():
        st = path.stat()
        return {"path": str(path), "files": 1, "bytes": st.st_size, "mtime_ns": st.st_mtime_ns}
    files = size = latest = 0
    for root, _dirs, names in os.walk(path):
        for name in names:
            try:
                st = os.stat(os.path.join(root, name))
            except OSError:
                continue
            files += 1
            size += st.st_size
            latest = max(latest, st.st_mtime_ns)
    return {"path": str(path), "files": files, "bytes": size, "mtime_ns": latest}
