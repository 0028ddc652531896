"""YAML files a user hands to slslam (configs, EuRoC ``sensor.yaml``), read defensively.

- size: a file over ``max_bytes`` (1 MiB by default; a real config or sensor.yaml is a few KB) is
  refused before it is read, so a mistaken or hostile file cannot stall the run;
- aliases (``*name``) are refused: nothing in slslam's files needs them, and a few lines of nested
  aliases ("billion laughs") expand to gigabytes. Nesting depth and node count are bounded too;
- a key given twice in one mapping is refused (PyYAML keeps the last one silently, so a typo'd
  copy-paste would change a value without a word);
- a FIFO, device or folder is refused before it is opened (a FIFO would block the read);
- the C loader (``yaml.CSafeLoader``, libyaml) is used when PyYAML has it: ~10x faster than the
  pure-Python loader, and only safe tags either way;
- messages name the file and the line, and never print a value whole (see :func:`short_repr`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from slslam.errors import InputError
from slslam.files import special_file_kind

MAX_YAML_BYTES = 1 << 20  # 1 MiB
MAX_DEPTH = 64  # nested mappings / lists
MAX_NODES = 100_000  # scalars, mappings and lists in one file
REPR_LIMIT = 60  # characters of a value shown in a message

SafeLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def short_repr(value: Any, limit: int = REPR_LIMIT) -> str:
    """``repr(value)`` cut to ``limit`` characters (with ``...``), for messages about bad values."""
    try:
        text = repr(value)
    except Exception:  # a repr that fails (e.g. an int over Python's digit limit)
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _describe(exc: yaml.YAMLError) -> str:
    """A YAML error in one short line: the problem and where (the snippet is left out)."""
    if isinstance(exc, yaml.MarkedYAMLError) and exc.problem_mark is not None:
        mark = exc.problem_mark
        problem = short_repr(exc.problem or "syntax error", 120).strip("'\"")
        return f"{problem} at line {mark.line + 1}, column {mark.column + 1}"
    return short_repr(str(exc).splitlines()[0] if str(exc) else type(exc).__name__, 120)


def _check_structure(text: str, source: Path, error: type[InputError]) -> None:
    """Scan the event stream (no construction, no expansion) for aliases, depth, size and keys
    given twice in one mapping."""
    depth = nodes = 0
    # one entry per open collection: (keys seen so far, [next node is a key]) for a mapping,
    # None for a sequence
    open_collections: list[tuple[set[str], list[bool]] | None] = []

    def node_done() -> None:
        top = open_collections[-1] if open_collections else None
        if top is not None:
            top[1][0] = not top[1][0]

    for event in yaml.parse(text, Loader=SafeLoader):
        if isinstance(event, yaml.AliasEvent):
            line = event.start_mark.line + 1 if event.start_mark else "?"
            raise error(
                source,
                f"YAML alias '*{short_repr(event.anchor, 30).strip(chr(39))}' at line {line}: "
                "aliases and anchors are not accepted in slslam input files",
            )
        if isinstance(event, (yaml.ScalarEvent, yaml.CollectionStartEvent)):
            nodes += 1
            if nodes > MAX_NODES:
                raise error(source, f"more than {MAX_NODES} YAML nodes: not a slslam input file")
        if isinstance(event, yaml.CollectionStartEvent):
            depth += 1
            if depth > MAX_DEPTH:
                line = event.start_mark.line + 1 if event.start_mark else "?"
                raise error(source, f"YAML nested deeper than {MAX_DEPTH} levels at line {line}")
        elif isinstance(event, yaml.CollectionEndEvent):
            depth -= 1
        if isinstance(event, yaml.ScalarEvent):
            top = open_collections[-1] if open_collections else None
            if top is not None and top[1][0]:
                if event.value in top[0]:
                    line = event.start_mark.line + 1 if event.start_mark else "?"
                    raise error(
                        source,
                        f"key {short_repr(event.value, 40)} given twice in one mapping (again at "
                        f"line {line}): remove one",
                    )
                top[0].add(event.value)
            node_done()
        elif isinstance(event, yaml.MappingStartEvent):
            open_collections.append((set(), [True]))
        elif isinstance(event, yaml.SequenceStartEvent):
            open_collections.append(None)
        elif isinstance(event, yaml.CollectionEndEvent):
            open_collections.pop()
            node_done()


def read_yaml(
    path: str | Path,
    error: type[InputError] = InputError,
    max_bytes: int = MAX_YAML_BYTES,
    strip_opencv_header: bool = False,
) -> Any:
    """Parse the YAML file at ``path`` under the limits above; problems raise ``error(path, ...)``.

    ``strip_opencv_header`` drops OpenCV's ``%YAML:1.0`` first line, which PyYAML rejects.
    """
    path = Path(path)
    kind = special_file_kind(path)
    if kind == "missing":
        raise error(path, "file not found")
    if kind is not None:
        raise error(path, f"is {kind}, not a YAML file")
    size = path.stat().st_size
    if size > max_bytes:
        raise error(path, f"file is {size} bytes; YAML inputs are limited to {max_bytes} bytes")
    raw = path.read_bytes()[: max_bytes + 1]  # the file may have grown since stat()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(path, f"not UTF-8 text (byte {exc.start}): not a YAML file") from None
    if strip_opencv_header and text.startswith("%YAML:"):
        text = text.split("\n", 1)[1] if "\n" in text else ""
    try:
        _check_structure(text, path, error)
        return yaml.load(text, Loader=SafeLoader)  # SafeLoader: only plain YAML types
    except InputError:
        raise
    except yaml.YAMLError as exc:
        raise error(path, f"not valid YAML ({_describe(exc)})") from None
    except (ValueError, RecursionError, OverflowError) as exc:
        # e.g. an integer with more digits than Python converts (ValueError from int()).
        raise error(path, f"not valid YAML ({short_repr(str(exc), 120)})") from None
