"""Roadway centrelines of the simulator presets (floor centre, z = 0 on the floor, metres)."""

from __future__ import annotations

import numpy as np

#: Spacing of the returned centreline points [m].
STEP_M = 0.25


def _arc(center: np.ndarray, radius: float, start: float, end: float) -> np.ndarray:
    n = max(int(abs(end - start) * radius / STEP_M), 2)
    a = np.linspace(start, end, n)
    return np.column_stack(
        [center[0] + radius * np.cos(a), center[1] + radius * np.sin(a), np.zeros(n)]
    )


def _line(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    n = max(int(np.linalg.norm(b - a) / STEP_M), 2)
    return np.linspace(a, b, n)


def _join(*parts: np.ndarray) -> np.ndarray:
    """Concatenate polyline parts, dropping repeated junction points."""
    out = [parts[0]]
    for part in parts[1:]:
        out.append(part[1:] if np.allclose(part[0], out[-1][-1]) else part)
    return np.concatenate(out)


def straight(length_m: float = 80.0) -> np.ndarray:
    """A long straight roadway along +x: the LiDAR paper's degenerate "long corridor"."""
    return _line(np.zeros(3), np.array([length_m, 0.0, 0.0]))


def loop(length_m: float = 40.0, radius_m: float = 10.0) -> np.ndarray:
    """A closed shaft-bottom yard loop (two straights joined by half circles); first == last."""
    L, r = length_m, radius_m
    return _join(
        _line(np.array([0.0, 0, 0]), np.array([L, 0, 0])),
        _arc(np.array([L, r]), r, -np.pi / 2, np.pi / 2),
        _line(np.array([L, 2 * r, 0]), np.array([0.0, 2 * r, 0])),
        _arc(np.array([0.0, r]), r, np.pi / 2, 3 * np.pi / 2),
    )


def junction_roadways(
    main_m: float = 60.0, branch_at_m: float = 30.0, branch_m: float = 25.0
) -> list[np.ndarray]:
    """A main roadway along +x and a branch leaving it at a right angle towards +y."""
    main = _line(np.zeros(3), np.array([main_m, 0.0, 0.0]))
    branch = _line(np.array([branch_at_m, 0.0, 0.0]), np.array([branch_at_m, branch_m, 0.0]))
    return [main, branch]


def junction_path(
    branch_at_m: float = 30.0, branch_m: float = 25.0, turn_radius_m: float = 4.0
) -> np.ndarray:
    """The robot's path through the junction: along the main roadway, then into the branch."""
    r = turn_radius_m
    return _join(
        _line(np.zeros(3), np.array([branch_at_m - r, 0.0, 0.0])),
        _arc(np.array([branch_at_m - r, r]), r, -np.pi / 2, 0.0),
        _line(np.array([branch_at_m, r, 0.0]), np.array([branch_at_m, branch_m - 2.0, 0.0])),
    )


def dead_end_roadways(
    main_m: float = 36.0, branch_at_m: float = 10.0, branch_m: float = 30.0
) -> list[np.ndarray]:
    """A main roadway along +x and a dead-end branch leaving it at a right angle towards +y
    (the branch's last point is where its face stands: see ``roadway.end_cap``)."""
    return junction_roadways(main_m, branch_at_m, branch_m)


def dead_end_path(
    branch_at_m: float = 10.0, branch_m: float = 30.0, turn_radius_m: float = 4.0
) -> np.ndarray:
    """The robot's path into the dead end: a short main roadway stretch, the turn, then up the
    branch to 2 m before its face."""
    return junction_path(branch_at_m, branch_m, turn_radius_m)
