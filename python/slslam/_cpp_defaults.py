"""Defaults read from the C++ option structs, the one place they are written: the Python config
sections and the front ends' option dataclasses take their defaults from here."""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def core_attribute(options: Any, path: str) -> Any:
    """The value at a dotted attribute path of the C++ options (``"mapping.ba.line_weight"``)."""
    *parents, last = path.split(".")
    for part in parents:
        options = getattr(options, part)
    return getattr(options, last)


def as_written(value: Any) -> Any:
    """A C++ default as its source writes it: a ``float`` field (0.9f reaches Python as
    0.8999999761581421) becomes the shortest decimal that is the same float32 (0.9)."""
    if isinstance(value, float) and math.isfinite(value):
        single = np.float32(value)
        if float(single) == value:  # a float32 value: print it as float32
            return float(str(single))
    return value
