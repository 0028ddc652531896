"""LiDAR scan registration (the LiDAR paper's) through the C++ core, which must be built with PCL.

    import numpy as np
    from slslam.lidar import register

    T_target_source = register(source_xyz, target_xyz)            # (4, 4) float64
    result = register_full(source_xyz, target_xyz, method="ndt")   # transform, fitness, times

Points are float arrays of shape (N, 3) (x, y, z) or (N, 4) (x, y, z, intensity) in metres.
Methods: ``fpfh_sac_ia_icp`` (default: FPFH + SAC-IA coarse, coarse-to-fine ICP), ``ndt``,
``pfh_sac_ia_icp`` and ``icp`` (from identity). The transform maps source points into the target
frame. Parameters are those of the C++ ``RegistrationOptions`` (see
``cpp/slslam/lidar/registration.h``), passed as keyword arguments.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from slslam import _core
from slslam.errors import InputError

__all__ = ["METHODS", "available", "make_options", "read_points", "register", "register_full"]

METHODS = ("fpfh_sac_ia_icp", "ndt", "pfh_sac_ia_icp", "icp")


def available() -> bool:
    """True when slslam._core was built with the LiDAR module (SLSLAM_WITH_PCL=ON)."""
    return hasattr(_core, "register_clouds")


def _require_core() -> None:
    if not available():
        raise RuntimeError(
            "slslam._core was built without PCL: LiDAR registration is unavailable "
            "(install libpcl-dev and rebuild with -DSLSLAM_WITH_PCL=ON)"
        )


def make_options(**fields: Any) -> Any:
    """A ``_core.RegistrationOptions`` with the given fields set (unknown names raise)."""
    _require_core()
    options = _core.RegistrationOptions()
    for name, value in fields.items():
        if not hasattr(options, name):
            raise InputError(None, f"unknown registration option '{name}'")
        setattr(options, name, value)
    options.check()
    return options


def _points(array: Any, name: str) -> np.ndarray:
    points = np.ascontiguousarray(array, dtype=np.float32)
    if points.ndim != 2 or points.shape[1] not in (3, 4):
        raise InputError(name, f"expected shape (N, 3) or (N, 4), got {points.shape}")
    if not np.isfinite(points).all():
        raise InputError(name, "contains NaN or infinite values")
    return points


def read_points(path: str | Path) -> np.ndarray:
    """A KITTI Velodyne .bin, PCD or PLY file as float32 (N, 4): x, y, z [m], intensity (0 when
    the file has none). Non-finite points of organised clouds are dropped. A missing or malformed
    file raises ``InputError`` naming it."""
    _require_core()
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "point cloud file not found")
    try:
        return np.asarray(_core.read_point_cloud(str(path)))
    except ValueError as exc:
        raise InputError(path, str(exc)) from exc


def register_full(source: Any, target: Any, method: str = "fpfh_sac_ia_icp", **options: Any) -> Any:
    """Registers source onto target; returns the core's RegistrationResult (transform, fitness,
    inlier_rmse, iterations, converged, per-stage times in ms)."""
    _require_core()
    if method not in METHODS:
        raise InputError(None, f"unknown method '{method}' (expected one of {', '.join(METHODS)})")
    core_method = getattr(_core.RegistrationMethod, method.upper())
    return _core.register_clouds(
        _points(source, "source"), _points(target, "target"), make_options(**options), core_method
    )


def register(
    source: Any, target: Any, method: str = "fpfh_sac_ia_icp", **options: Any
) -> np.ndarray:
    """T_target_source (4, 4) float64 mapping source points into the target frame."""
    return np.asarray(register_full(source, target, method, **options).transform, dtype=np.float64)
