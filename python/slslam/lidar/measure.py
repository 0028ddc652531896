"""Roadway dimensions measured on a LiDAR map (as in the LiDAR paper, which measures corridor
length and width on its map against a laser range finder).

Cross-sections are cut perpendicular to the driven path (the robot drives along the roadway): the
map points within ``slab_m`` of each section plane, in the band of heights where the walls are
vertical, give the width as the distance between the two walls, each taken as the median of the
outermost band of lateral coordinates (robust to range noise and to the arches, pipe and cables
standing off the walls).
The length of a straight roadway is the extent of the map along its axis.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def cross_section_widths(
    map_points: np.ndarray,
    path_xyz: np.ndarray,
    floor_z: np.ndarray | None = None,
    spacing_m: float = 1.0,
    slab_m: float = 0.1,
    band_m: tuple[float, float] = (0.3, 1.8),
    min_points: int = 20,
    outer_m: float = 0.1,
    section_radius_m: float = 6.0,
) -> np.ndarray:
    """Roadway width [m] at stations every ``spacing_m`` along the path (NaN where a section
    has fewer than ``min_points`` wall points). ``band_m``: heights above the floor (the lowest
    map points of the section) where the walls are measured."""
    steps = np.linalg.norm(np.diff(path_xyz, axis=0), axis=1)
    s = np.r_[0.0, np.cumsum(steps)]
    stations = np.arange(spacing_m, s[-1] - spacing_m, spacing_m)
    widths = np.full(len(stations), np.nan)
    # Each section needs the points near its centre only: a kd-tree on x, y keeps the cost per
    # section independent of the map's size.
    tree = cKDTree(map_points[:, :2])
    for k, st in enumerate(stations):
        i = int(np.clip(np.searchsorted(s, st), 1, len(path_xyz) - 1))
        centre = path_xyz[i]
        tangent = path_xyz[min(i + 5, len(path_xyz) - 1)] - path_xyz[max(i - 5, 0)]
        tangent[2] = 0.0
        tangent = _unit(tangent)
        left = np.array([-tangent[1], tangent[0], 0.0])
        rel = map_points[tree.query_ball_point(centre[:2], r=section_radius_m)] - centre
        section = rel[np.abs(rel @ tangent) < slab_m]
        if len(section) < min_points:
            continue
        floor = np.percentile(section[:, 2], 2)
        height = section[:, 2] - floor
        wall = section[(height > band_m[0]) & (height < band_m[1])]
        if len(wall) < min_points:
            continue
        lateral = wall @ left
        # Each wall at the median of its outermost points (within outer_m of the 98th / 2nd
        # percentile): range noise spreads a wall symmetrically about it; arches, the pipe and
        # the cables stand inside and stay out of the band.
        hi, lo = np.percentile(lateral, 98), np.percentile(lateral, 2)
        widths[k] = np.median(lateral[lateral > hi - outer_m]) - np.median(
            lateral[lateral < lo + outer_m]
        )
    return widths


def straight_length(map_points: np.ndarray, path_xyz: np.ndarray) -> float:
    """Extent [m] of the map along the axis of a straight path (0.1 / 99.9 percentiles)."""
    axis = path_xyz[-1, :2] - path_xyz[0, :2]
    axis = axis / np.linalg.norm(axis)
    along = map_points[:, :2] @ axis
    return float(np.percentile(along, 99.9) - np.percentile(along, 0.1))


def measure_roadway(map_points: np.ndarray, path_xyz: np.ndarray, preset: str) -> dict:
    """Width statistics along the path, and the length for the straight preset."""
    widths = cross_section_widths(map_points, path_xyz)
    valid = widths[np.isfinite(widths)]
    out: dict = {
        "sections": len(widths),
        "sections_measured": len(valid),
        "width_median_m": float(np.median(valid)) if len(valid) else None,
        "width_mean_m": float(np.mean(valid)) if len(valid) else None,
        "width_std_m": float(np.std(valid)) if len(valid) else None,
    }
    if preset == "straight":
        out["length_m"] = straight_length(map_points, path_xyz)
    return out
