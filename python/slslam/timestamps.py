"""Time in slslam: an instant is an integer count of nanoseconds (``t_ns``, as the readers'
``timestamps_ns`` and the core's frames and IMU samples hold it); float seconds are a view of it
for people and float-second formats (TUM, evo). The conversions match the core's
(cpp/slslam/core/time.h), so a time given in seconds lands on the same nanosecond either side.
"""

from __future__ import annotations

import math

import numpy as np

#: int64's range [ns] (about +-292 years around the clock's zero).
INT64_MIN = -(2**63)
INT64_MAX = 2**63 - 1


def ns_from_seconds(t_s: float) -> int:
    """Seconds (an instant or a duration) as the nearest nanosecond: whole seconds and the
    fraction converted apart, so a Unix time keeps its nanoseconds (``t_s * 1e9`` rounds them to
    256). Raises ``ValueError`` for a value that is not finite or beyond int64 nanoseconds."""
    t = float(t_s)
    if not math.isfinite(t) or abs(t) > 9.2e9:
        raise ValueError(f"{t_s!r} s is not finite or beyond int64 nanoseconds")
    whole = math.floor(t)
    return int(whole) * 1_000_000_000 + math.floor((t - whole) * 1e9 + 0.5)


def seconds_from_ns(t_ns: int) -> float:
    """Nanoseconds as float seconds: whole seconds and the remainder apart (``t_ns / 1e9``
    would first round a Unix time's int to 256 ns), as the core's ``Seconds``."""
    whole, rest = divmod(int(t_ns), 1_000_000_000)
    return whole + rest / 1e9


def seconds_from_ns_array(t_ns: np.ndarray) -> np.ndarray:
    """:func:`seconds_from_ns` over an int64 array."""
    t = np.asarray(t_ns, dtype=np.int64)
    whole, rest = np.divmod(t, 1_000_000_000)
    return whole.astype(np.float64) + rest / 1e9
