"""Writing or checking a file a script generates (make_stubs.py, make_config_docs.py): one
``--check`` behaviour for all of them."""

from __future__ import annotations

import sys
from pathlib import Path


def write_or_check(path: Path, text: str, check: bool, command: str) -> int:
    """With ``check``: exit status 1 (and a line naming ``command`` on stderr) when ``path``
    differs from ``text``, 0 when it matches; without: writes ``text`` to ``path``."""
    if check:
        if path.read_text(encoding="utf-8") != text:
            print(f"{path} is stale: run {command}", file=sys.stderr)
            return 1
        print(f"{path} is up to date")
        return 0
    path.write_text(text, encoding="utf-8")
    print(f"wrote {path}")
    return 0
