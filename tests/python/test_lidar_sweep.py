"""The simulator's spinning LiDAR sweep (per-point time, motion distortion) and the LiDAR + IMU
sequence reader of ``slslam lidar run``."""

from __future__ import annotations

import numpy as np
import pytest

from slslam import _core

if not hasattr(_core, "LidarOdometry"):
    pytest.skip("slslam._core built without the LiDAR module", allow_module_level=True)

from slslam.errors import DatasetError
from slslam.lidar.datasets import open_lidar_sequence
from slslam.sim import SimOptions, Simulator


@pytest.fixture(scope="module")
def small_sequence(tmp_path_factory):
    """Two seconds of the loop preset, LiDAR + IMU only (20 sweeps)."""
    out = tmp_path_factory.mktemp("lidar_seq")
    Simulator(SimOptions(preset="loop", frames=40, cameras=False)).write(out, progress=False)
    return out


def test_sweep_points_lie_on_the_surface_at_their_own_time(small_sequence):
    """Each point, moved with the sensor pose at its own time, lies on the roadway; moved with
    the pose at the sweep start it does not (the distortion is real at 0.8 m/s)."""
    sim = Simulator(SimOptions(preset="loop", frames=40, cameras=False, noise=False))
    t = 1.5
    scan, T_start, times = sim._render_sweep(t, np.random.default_rng(0))
    assert scan.shape[0] == times.shape[0] > 10000
    assert 0.0 < times.min() and times.max() < 0.1
    T_point = sim.trajectory.pose(t + times.astype(float)) @ sim.lidar.T_body_lidar
    world = np.einsum("nij,nj->ni", T_point[:, :3, :3], scan[:, :3]) + T_point[:, :3, 3]
    origins = T_point[:, :3, 3]
    # Re-cast each point's ray from its own origin: the hit distance equals the range.
    dirs = world - origins
    ranges = np.linalg.norm(dirs, axis=1)
    pick = np.linspace(0, len(world) - 1, 300).astype(int)
    for i in pick[:50]:
        hit = sim.scene.cast(origins[i], (dirs[i] / ranges[i])[None])
        assert hit.t[0] == pytest.approx(ranges[i], abs=1e-3)
    skewed = scan[:, :3] @ T_start[:3, :3].T + T_start[:3, 3]
    assert np.median(np.linalg.norm(skewed - world, axis=1)) > 0.02


def test_written_sequence_reads_back_with_point_times(small_sequence):
    seq = open_lidar_sequence(small_sequence)
    assert len(seq) == 20
    assert seq.imu is not None and seq.imu.t_ns[0] <= seq.t_ns[0]
    assert seq.scan_period_s == pytest.approx(0.1)
    np.testing.assert_allclose(seq.T_body_sensor[:3, 3], [0.1, 0.0, 1.4])
    sweep = seq.sweep(3)
    assert sweep.points.shape[1] == 4 and sweep.point_time_s.shape == (len(sweep.points),)
    assert seq.groundtruth is not None and seq.groundtruth_frame == "body"
    assert not (small_sequence / "mav0" / "cam0").exists()  # cameras were off


def test_reader_names_the_bad_file(small_sequence, tmp_path):
    with pytest.raises(DatasetError, match=r"lidar0/data\.csv"):
        open_lidar_sequence(tmp_path)
    seq = open_lidar_sequence(small_sequence)
    bad = seq.time_paths[0]
    original = bad.read_bytes()
    try:
        bad.write_bytes(original[:-8])
        with pytest.raises(DatasetError, match="point times"):
            seq.sweep(0)
    finally:
        bad.write_bytes(original)
