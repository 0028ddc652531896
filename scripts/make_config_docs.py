"""The configuration reference: docs/configuration.md, generated from the options themselves.

    python scripts/make_config_docs.py          # rewrite docs/configuration.md
    python scripts/make_config_docs.py --check  # exit 1 when the checked-in page differs

Every key of ``slslam.config.Config`` with its default (the C++ option struct's, for the keys the
core reads), its allowed range (the one the C++ ``Check()`` enforces; tests/python/test_config.py
probes both ends of each), the C++ option it sets and its meaning (the comment beside it in
configs/default.yaml). Run it after changing an option; tests/python/test_config_docs.py fails
while the checked-in page is stale.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import typing
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "configuration.md"
YAML = ROOT / "configs" / "default.yaml"


def yaml_comments(path: Path) -> dict[str, str]:
    """Dotted key -> the comment beside it in the YAML file and on the comment-only lines that
    continue it (indented under it), or above it (a comment block right before the key, for a
    key without a comment of its own beside it too)."""
    comments: dict[str, str] = {}
    stack: list[tuple[int, str]] = []  # (indent, key) of the open mappings
    pending: list[str] = []  # a comment block waiting for the key below it
    last: str | None = None
    last_indent = -1
    for raw in path.read_text(encoding="utf-8").splitlines():
        if not raw.strip():
            pending, last = [], None
            continue
        indent = len(raw) - len(raw.lstrip())
        text = raw.strip()
        if text.startswith("#"):
            note = text.lstrip("#").strip()
            if last is not None and indent > last_indent:
                comments[last] = f"{comments.get(last, '')} {note}".strip()
            else:
                pending.append(note)
                last = None
            continue
        match = re.match(r"([A-Za-z_][\w]*):\s*(.*)$", text)
        if match is None:
            continue
        key, rest = match.groups()
        while stack and stack[-1][0] >= indent:
            stack.pop()
        dotted = ".".join([k for _, k in stack] + [key])
        if indent == 0:
            pending = []  # the file's own header, or a note on the layout: not this key's
        value, _, note = rest.partition("#")
        parts = [*pending, note.strip()] if note.strip() else pending
        if parts:
            comments[dotted] = " ".join(p for p in parts if p)
        pending = []
        if not value.strip():  # a mapping: its keys follow, more indented
            stack.append((indent, key))
        # Comment-only lines below continue this key's comment when it has one beside it (a
        # mapping without one: they are its first key's).
        last, last_indent = (dotted, indent) if note.strip() else (None, -1)
    return comments


def core_tables() -> dict[type, list[tuple[str, dict[str, tuple[str, ...]]]]]:
    """Config dataclass -> the (C++ struct, key table) pairs its mirrored keys come from."""
    from slslam import config as c

    return {
        c.TrackingConfig: [("TrackerOptions", c.TRACKING_TO_CORE)],
        c.LoopClosingConfig: [("TrackerOptions", c.LOOP_CLOSING_TO_CORE)],
        c.ImuConfig: [("TrackerOptions", c.IMU_TO_CORE)],
        c.DynamicCellConfig: [("TrackerOptions", c.DYNAMIC_CELLS_TO_CORE)],
        c.GridConfig: [("GridLimitOptions", c.GRID_TO_CORE)],
        c.FeaturesConfig: [("LineExtractorOptions", c.LINES_TO_CORE)],
    }


def show(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(show(v) for v in value) + "]"
    text = str(value.value if hasattr(value, "value") and not isinstance(value, str) else value)
    return text.replace("|", "\\|")


def rows(obj: Any, prefix: str, comments: dict[str, str], out: dict[str, list[str]]) -> None:
    """One table row per leaf key of dataclass instance ``obj``, grouped by its section."""
    from slslam.config import option_range

    tables = core_tables().get(type(obj), [])
    hints = typing.get_type_hints(type(obj))
    for f in dataclasses.fields(obj):
        key = f"{prefix}.{f.name}"
        value = getattr(obj, f.name)
        if dataclasses.is_dataclass(hints[f.name]) and dataclasses.is_dataclass(value):
            rows(value, key, comments, out)
            continue
        bounds = option_range(type(obj), f)
        core = next(
            (
                f"`{struct}.{'`, `'.join(table[f.name])}`"
                for struct, table in tables
                if f.name in table
            ),
            "",
        )
        meaning = comments.get(key, "").replace("|", "\\|")
        out.setdefault(prefix, []).append(
            f"| `{f.name}` | `{show(value)}` | {bounds if bounds else ''} | {core} | {meaning} |"
        )


def render() -> str:
    from slslam.config import Config

    comments = yaml_comments(YAML)
    sections: dict[str, list[str]] = {}
    config = Config()
    for f in dataclasses.fields(config):
        rows(getattr(config, f.name), f.name, comments, sections)
    lines = [
        "# Configuration reference",
        "",
        "<!-- Generated by scripts/make_config_docs.py from slslam.config and the C++ option",
        "     structs it mirrors; do not edit by hand. -->",
        "",
        "Every key a YAML config may set (`slslam run --config FILE`, `slslam.load_config`), by",
        "section. **Default**: the value without a config; for a key the C++ core reads it is the",
        "C++ option struct's own default (`python/slslam/_cpp_defaults.py` reads it from there).",
        "**Range**: the values accepted, in interval notation; the C++ options' `Check()` enforces",
        "the same ends (tests/python/test_config.py probes both sides of each), and a value",
        "outside is refused naming the file and key. **C++ option**: the field of the core's",
        "options it sets. **Meaning**: the comment in `configs/default.yaml`, which lists every",
        "key with its default. A point front end's preset (`python/slslam/presets/`) changes",
        "some defaults when that front end is chosen; `slslam config` prints what a run would",
        "use.",
        "",
    ]
    for section, body in sections.items():
        lines += [f"## `{section}`", ""]
        if comments.get(section):
            note = comments[section].rstrip(".")
            lines += [note[0].upper() + note[1:] + ".", ""]
        lines += [
            "| key | default | range | C++ option | meaning |",
            "|---|---|---|---|---|",
            *body,
            "",
        ]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 when the page is stale")
    args = parser.parse_args()
    # (imported here: the tests load this file for render() alone, without scripts/ on the path)
    from generated_file import write_or_check

    return write_or_check(PAGE, render(), args.check, "python scripts/make_config_docs.py")


if __name__ == "__main__":
    raise SystemExit(main())
