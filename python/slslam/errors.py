"""Exceptions slslam raises for bad input.

Every message names the file (or argument) and the problem in one line, so the command line can
print it without a traceback. All derive from :class:`ValueError` as well, so code that already
catches ``ValueError`` keeps working.
"""

from __future__ import annotations

from pathlib import Path


class SlslamError(Exception):
    """Base class of every error slslam raises on purpose."""


class InputError(SlslamError, ValueError):
    """An input (file, folder, array, option) is missing or malformed."""

    def __init__(self, source: str | Path | None, problem: str) -> None:
        self.source = None if source is None else str(source)
        self.problem = problem
        super().__init__(problem if source is None else f"{source}: {problem}")


class DatasetError(InputError):
    """A dataset folder does not have the expected layout or content."""


class CalibrationError(InputError):
    """A calibration file is missing keys or holds invalid values."""


class TrajectoryFileError(InputError):
    """A trajectory file is empty, malformed, non-monotonic or holds non-finite poses."""
