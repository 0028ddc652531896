"""LiDAR registration through the bindings: numpy in, 4x4 out, clear errors on bad input."""

from __future__ import annotations

import numpy as np
import pytest

from slslam import _core

if not hasattr(_core, "register_clouds"):
    pytest.skip("slslam._core built without PCL (no register_clouds)", allow_module_level=True)

from slslam.lidar import register, register_full


def _scene(n: int = 30000, seed: int = 0) -> np.ndarray:
    """Floor, two walls and a cylinder around the origin, (n, 3) float32."""
    rng = np.random.default_rng(seed)
    a, b = rng.random(n), rng.random(n)
    part = np.arange(n) % 4
    pts = np.zeros((n, 3))
    floor, wx, wy, cyl = (part == k for k in range(4))
    pts[floor] = np.column_stack([-15 + 30 * a[floor], -12 + 27 * b[floor], 0 * a[floor]])
    pts[wx] = np.column_stack([15 + 0 * a[wx], -12 + 27 * a[wx], 4 * b[wx]])
    pts[wy] = np.column_stack([-15 + 30 * a[wy], -12 + 0 * a[wy], 4 * b[wy]])
    th = 2 * np.pi * a[cyl]
    pts[cyl] = np.column_stack([-6 + 0.8 * np.cos(th), 4 + 0.8 * np.sin(th), 3 * b[cyl]])
    return pts.astype(np.float32)


def _transform(yaw_deg: float, t: tuple[float, float, float]) -> np.ndarray:
    c, s = np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:3, 3] = t
    return T


OPTIONS = dict(
    min_range_m=0.0,
    fine_voxel_m=0.25,
    coarse_voxel_m=0.75,
    feature_radius_m=2.0,
    icp_iterations_fine=50,
    icp_max_corr_fine_m=0.5,
)


@pytest.mark.parametrize("method", ["fpfh_sac_ia_icp", "icp"])
def test_recovers_a_known_transform(method):
    source = _scene()
    truth = _transform(8.0, (0.6, -0.3, 0.05))
    target = (source @ truth[:3, :3].T + truth[:3, 3]).astype(np.float32)
    T = register(source, target, method=method, **OPTIONS)
    assert T.shape == (4, 4) and T.dtype == np.float64
    np.testing.assert_allclose(T, truth, atol=2e-3)
    result = register_full(source, target, method=method, **OPTIONS)
    assert result.fitness > 0.9 and result.total_ms > 0


def test_bad_shapes_and_nan_raise_value_error():
    good = _scene(2000)
    with pytest.raises(ValueError, match="shape"):
        register(good[:, :2], good)
    with pytest.raises(ValueError, match="shape"):
        _core.register_clouds(good[:, :2], good)
    bad = good.copy()
    bad[5, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        register(good, bad)
    with pytest.raises(ValueError, match="NaN"):
        _core.register_clouds(good, bad)
    with pytest.raises(ValueError, match="method"):
        register(good, good, method="go-icp")
    with pytest.raises(ValueError, match="fine_voxel_m"):
        register(good, good, fine_voxel_m=0.0)


def test_read_points_reads_kitti_pcd_and_ply_and_names_bad_files(tmp_path):
    from slslam.errors import InputError
    from slslam.lidar import read_points

    from conftest import shared_path

    kitti = shared_path("lidar", "kitti00_scancontext", "000094.bin")
    raw = np.fromfile(kitti, dtype=np.float32).reshape(-1, 4)
    points = read_points(kitti)
    assert points.dtype == np.float32 and np.array_equal(points, raw)
    gicp = shared_path("lidar", "gicp_pairs")
    ply = read_points(gicp / "small_gicp_source.ply")
    pcd = read_points(gicp / "fast_gicp_251371071.pcd")
    # The two files hold the same HDL-32E scan in two formats.
    assert ply.shape == pcd.shape == (69792, 4)
    assert np.allclose(np.sort(ply[:, 0]), np.sort(pcd[:, 0]))
    with pytest.raises(InputError, match="not found"):
        read_points(tmp_path / "missing.pcd")
    bad = tmp_path / "bad.bin"
    bad.write_bytes(b"123")  # not a multiple of 16 bytes
    with pytest.raises(InputError, match=r"bad\.bin"):
        read_points(bad)
