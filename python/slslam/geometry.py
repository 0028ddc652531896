"""Small rigid-transform helpers on 4x4 numpy matrices.

Convention used everywhere in slslam: ``T_a_b`` is the pose of frame ``b`` in frame ``a``; it maps
coordinates of a point in ``b`` to ``a`` (``p_a = T_a_b @ p_b``). Translations are in metres.
"""

from __future__ import annotations

import numpy as np

#: A rotation block is accepted as orthonormal within this tolerance (calibration files carry
#: about ten significant digits).
ROTATION_TOLERANCE = 1e-6


def is_rigid_transform(T: np.ndarray, tol: float = ROTATION_TOLERANCE) -> bool:
    """True when ``T`` is a finite 4x4 matrix with a proper rotation block and last row 0 0 0 1."""
    T = np.asarray(T, dtype=float)
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        return False
    R = T[:3, :3]
    return bool(
        np.linalg.norm(R @ R.T - np.eye(3)) < tol
        and np.linalg.det(R) > 0.0
        and np.allclose(T[3], [0.0, 0.0, 0.0, 1.0])
    )


def invert_transform(T: np.ndarray) -> np.ndarray:
    """Inverse of a rigid 4x4 transform (uses R^T, exact for rotations)."""
    T = np.asarray(T, dtype=float)
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out
