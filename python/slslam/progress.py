"""Progress reporting: a live bar on a terminal, a short line every few seconds in a log.

tqdm redraws its bar in place with carriage returns; in a file or a CI log every redraw becomes a
line (a 600-frame run wrote about 600 of them). Off a terminal the bar therefore refreshes at most
every ``LOG_INTERVAL_S`` seconds, and callers update their postfix without forcing a redraw.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from typing import TypeVar

from tqdm import tqdm

T = TypeVar("T")

#: Seconds between two progress lines when stderr is not a terminal.
LOG_INTERVAL_S = 10.0

_quiet = False


def set_quiet(quiet: bool) -> None:
    """Turns every progress bar of the process off (``slslam --quiet``) or back on."""
    global _quiet
    _quiet = bool(quiet)


def progress_bar(
    iterable: Iterable[T] | None, desc: str, unit: str, enabled: bool = True, **kwargs
) -> tqdm:
    """A tqdm bar over ``iterable`` on stderr: live on a terminal, one line every
    ``LOG_INTERVAL_S`` seconds otherwise; nothing when ``enabled`` is false or the process is
    quiet (:func:`set_quiet`)."""
    interactive = sys.stderr.isatty()
    options = (
        {"mininterval": 0.1} if interactive else {"mininterval": LOG_INTERVAL_S, "ascii": True}
    )
    options.update(kwargs)
    disable = not enabled or _quiet
    return tqdm(iterable, desc=desc, unit=unit, disable=disable, file=sys.stderr, **options)
