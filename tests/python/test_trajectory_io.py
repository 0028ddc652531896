import numpy as np
import pytest
from evo.core.trajectory import PosePath3D, PoseTrajectory3D

from slslam.datasets import detect_format, read_trajectory, write_trajectory
from slslam.errors import TrajectoryFileError

from conftest import shared_path


def _trajectory(n: int = 10) -> PoseTrajectory3D:
    t = np.arange(n) * 0.05 + 100.0
    xyz = np.column_stack([np.linspace(0, 1, n), np.sin(t), np.zeros(n)])
    angle = np.linspace(0, 0.5, n)
    quat = np.column_stack([np.cos(angle / 2), np.zeros(n), np.zeros(n), np.sin(angle / 2)])
    return PoseTrajectory3D(xyz, quat, t)


def test_tum_round_trip(tmp_path):
    traj = _trajectory()
    path = write_trajectory(tmp_path / "out" / "traj.tum", traj)
    assert detect_format(path) == "tum"
    back = read_trajectory(path)
    np.testing.assert_allclose(back.positions_xyz, traj.positions_xyz, atol=1e-9)
    np.testing.assert_allclose(back.timestamps, traj.timestamps, atol=1e-9)
    assert not (tmp_path / "out" / "traj.tum.partial").exists()


def test_kitti_round_trip_and_times_file(tmp_path):
    traj = _trajectory()
    path = write_trajectory(tmp_path / "traj.txt", traj, fmt="kitti")
    assert detect_format(path) == "kitti"
    back = read_trajectory(path)
    assert type(back) is PosePath3D
    np.testing.assert_allclose(back.poses_se3, traj.poses_se3, atol=1e-6)
    times = tmp_path / "times.txt"
    np.savetxt(times, traj.timestamps)
    timed = read_trajectory(path, kitti_times=times)
    assert isinstance(timed, PoseTrajectory3D)
    np.savetxt(times, traj.timestamps[:-1])
    with pytest.raises(TrajectoryFileError, match="has 9 timestamps for 10 poses"):
        read_trajectory(path, kitti_times=times)


def test_real_files_of_each_format():
    kitti = read_trajectory(shared_path("trajectories", "KITTI_00_gt.txt"))
    assert kitti.num_poses == 4541
    tum = read_trajectory(shared_path("trajectories", "freiburg1_xyz-groundtruth.txt"))
    assert detect_format(shared_path("trajectories", "freiburg1_xyz-groundtruth.txt")) == "tum"
    assert tum.num_poses > 1000
    euroc = read_trajectory(shared_path("euroc_groundtruth_leftcam", "V101_GT.txt"))
    assert euroc.num_poses == 2871
    assert euroc.timestamps[0] == pytest.approx(1403715274.312143104)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("", "empty"),
        ("# only a comment\n", "empty"),
        ("1 2 3\n", "cannot tell the format: first row has 3 columns"),
        ("1.0 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n", "not strictly increasing at pose 1"),
        ("1.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n", "not strictly increasing at pose 1"),
        ("1.0 0 0 0 0 0 0 1\n2.0 nan 0 0 0 0 0 1\n", "pose 1 contains NaN"),
        ("1.0 0 0 0 0 0 0 0\n", "pose 0 has a zero quaternion"),
        ("1.0 0 0 x 0 0 0 1\n", "not a valid TUM trajectory"),
    ],
)
def test_bad_files_name_the_file_and_problem(tmp_path, content, message):
    path = tmp_path / "bad.txt"
    path.write_text(content)
    with pytest.raises(TrajectoryFileError, match=message) as info:
        read_trajectory(path)
    assert str(path) in str(info.value)


def test_missing_file_and_unknown_format(tmp_path):
    with pytest.raises(TrajectoryFileError, match="trajectory file not found"):
        read_trajectory(tmp_path / "none.txt")
    path = write_trajectory(tmp_path / "a.tum", _trajectory())
    with pytest.raises(TrajectoryFileError, match="unknown trajectory format"):
        read_trajectory(path, "bag")  # type: ignore[arg-type]
    with pytest.raises(TrajectoryFileError, match="TUM output needs timestamps"):
        write_trajectory(tmp_path / "b.tum", PosePath3D(poses_se3=[np.eye(4)] * 3))
