"""KITTI ground truth in the Velodyne frame (poses.txt holds camera poses)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from slslam.errors import DatasetError


def _read_tr(path: Path) -> np.ndarray:
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("Tr:"):
            values = np.array(line.split()[1:], dtype=float)
            if values.size != 12:
                raise DatasetError(path, "'Tr:' must hold 12 numbers")
            T = np.eye(4)
            T[:3] = values.reshape(3, 4)
            return T
    raise DatasetError(path, "missing the 'Tr:' line (T_cam0_velo)")


def kitti_velodyne_poses(poses: Path, calib: Path) -> np.ndarray:
    """T_world_velo (N, 4, 4) = T_world_cam0 @ Tr, with the world at the first Velodyne pose."""
    try:
        rows = np.loadtxt(poses, ndmin=2, dtype=float)
    except ValueError as exc:
        raise DatasetError(poses, f"not a KITTI poses file ({exc})") from None
    if rows.shape[1] != 12:
        raise DatasetError(poses, f"expected 12 numbers per line, got {rows.shape[1]}")
    T = np.tile(np.eye(4), (len(rows), 1, 1))
    T[:, :3] = rows.reshape(-1, 3, 4)
    T = T @ _read_tr(calib)
    return np.linalg.inv(T[0]) @ T
