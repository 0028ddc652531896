"""Console output that wraps cleanly in a terminal and stays one line in a log, and help texts
whose paragraphs reflow to the terminal's width."""

from __future__ import annotations

import inspect
import re
import sys
from typing import Any

from rich.console import Console


def stdout_console() -> Console:
    """rich's console on stdout: word-wrapped to a terminal's width, unwrapped (one line per
    message) when stdout is a file, a pipe or a log."""
    return Console(soft_wrap=not sys.stdout.isatty())


def stderr_console() -> Console:
    """The same on stderr."""
    return Console(stderr=True, soft_wrap=not sys.stderr.isatty())


_KEEP = re.compile("^(\\s*([-*]|\\d+[.)]) |    |\x08)")


def reflow(text: str) -> str:
    """A docstring's paragraphs with their single line breaks joined (rich then wraps them at the
    terminal's width instead of at the source's); lists, indented blocks and ``\\b`` paragraphs
    stay as written."""
    paragraphs = inspect.cleandoc(text).split("\n\n")
    out = []
    for paragraph in paragraphs:
        lines = paragraph.split("\n")
        if any(_KEEP.match(line) for line in lines):
            out.append(paragraph)
        else:
            out.append(" ".join(line.strip() for line in lines))
    return "\n\n".join(out)


def reflow_help(app: Any) -> None:
    """Reflows the help of every command of a typer app and of its sub-apps (once: idempotent)."""
    for command in app.registered_commands:
        text = command.help or inspect.getdoc(command.callback) or ""
        if text:
            command.help = reflow(text)
    for group in app.registered_groups:
        if group.typer_instance is not None:
            reflow_help(group.typer_instance)
