"""Marked blocks in Markdown files, rewritten from a sweep's results.

A block is the text between two HTML comments, which Markdown does not show:

    <!-- slslam-bench:recovery begin -->
    (generated: replaced on every update)
    <!-- slslam-bench:recovery end -->

``slslam bench report SPEC --update README.md`` replaces what lies between the markers of the
spec's name; everything outside them is kept byte for byte.
"""

from __future__ import annotations

import re
from pathlib import Path

from slslam.errors import InputError


def markers(name: str) -> tuple[str, str]:
    return f"<!-- slslam-bench:{name} begin -->", f"<!-- slslam-bench:{name} end -->"


def replace_block(text: str, name: str, content: str, source: str | Path = "text") -> str:
    """``text`` with block ``name``'s content replaced; exactly one pair of markers must be
    there, begin before end."""
    begin, end = markers(name)
    starts = [m.start() for m in re.finditer(re.escape(begin), text)]
    ends = [m.start() for m in re.finditer(re.escape(end), text)]
    if not starts or not ends:
        raise InputError(
            source,
            f"no block {name!r}: add the lines '{begin}' and '{end}' where the results go",
        )
    if len(starts) > 1 or len(ends) > 1:
        raise InputError(source, f"block {name!r} is marked more than once")
    if ends[0] < starts[0]:
        raise InputError(source, f"block {name!r}: its end marker comes before its begin marker")
    head = text[: starts[0] + len(begin)]
    tail = text[ends[0] :]
    return f"{head}\n{content.strip()}\n{tail}"


def update_file(path: str | Path, name: str, content: str) -> bool:
    """Rewrites block ``name`` of the file at ``path`` (atomically); True when it changed."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "file to update not found")
    text = path.read_text(encoding="utf-8")
    new = replace_block(text, name, content, path)
    if new == text:
        return False
    tmp = path.with_name(path.name + ".partial")
    try:
        tmp.write_text(new, encoding="utf-8")
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)
    return True
