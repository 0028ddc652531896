"""KITTI readers: the shared raw drive, and small odometry / raw folders written here."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from slslam.datasets import KittiSequence, is_kitti, kitti_layout
from slslam.errors import CalibrationError, DatasetError
from slslam.tracking.run import open_dataset, tum_time

from conftest import shared_path

FX, CX, CY, BASELINE = 700.0, 31.5, 23.5, 0.5
SIZE = (64, 48)  # width, height


def _projection(x_m: float) -> str:
    P = np.array([[FX, 0, CX, -FX * x_m], [0, FX, CY, 0], [0, 0, 1, 0]], dtype=float)
    return " ".join(f"{v:.12e}" for v in P.ravel())


def _write_images(folder: Path, names: list[str], seed: int) -> None:
    from slslam import _core

    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    for name in names:
        image = rng.integers(0, 255, size=(SIZE[1], SIZE[0]), dtype=np.uint8)
        _core.write_image(str(folder / name), image)


def make_odometry(root: Path, n: int = 4, poses: bool = True) -> Path:
    seq = root / "sequences" / "07"
    names = [f"{i:06d}.png" for i in range(n)]
    _write_images(seq / "image_0", names, 0)
    _write_images(seq / "image_1", names, 1)
    lines = [f"P{k}: {_projection(x)}" for k, x in enumerate((0.0, BASELINE, 0.06, 0.56))]
    (seq / "calib.txt").write_text("\n".join([*lines, f"Tr: {' '.join(['0'] * 12)}"]) + "\n")
    (seq / "times.txt").write_text("".join(f"{0.1 * i:e}\n" for i in range(n)))
    if poses:
        (root / "poses").mkdir(parents=True, exist_ok=True)
        rows = [f"1 0 0 0 0 1 0 0 0 0 1 {0.5 * i}" for i in range(n)]
        (root / "poses" / "07.txt").write_text("\n".join(rows) + "\n")
    return seq


RAW_CALIB = """calib_time: 09-Jan-2012 13:57:47
corner_dist: 9.950000e-02
S_00: 1.392000e+03 5.120000e+02
S_rect_00: {w} {h}
P_rect_00: {p0}
S_01: 1.392000e+03 5.120000e+02
S_rect_01: {w} {h}
P_rect_01: {p1}
"""


def make_raw(root: Path, n: int = 4, calib_in_parent: bool = True) -> Path:
    drive = root / "2011_09_26" / "2011_09_26_drive_0042_sync"
    names = [f"{i:010d}.png" for i in range(n)]
    for cam, seed in (("image_00", 0), ("image_01", 1)):
        _write_images(drive / cam / "data", names, seed)
        stamps = [
            f"2011-09-26 13:02:{25 + i // 10:02d}.{(i % 10) * 100 + 7:03d}000000" for i in range(n)
        ]
        (drive / cam / "timestamps.txt").write_text("\n".join(stamps) + "\n")
    calib = RAW_CALIB.format(w=SIZE[0], h=SIZE[1], p0=_projection(0.0), p1=_projection(BASELINE))
    (drive.parent if calib_in_parent else drive).joinpath("calib_cam_to_cam.txt").write_text(calib)
    return drive


def test_odometry_sequence_frames_calibration_times_and_poses(tmp_path):
    seq_dir = make_odometry(tmp_path)
    assert kitti_layout(seq_dir) == "odometry"
    seq = open_dataset(seq_dir)
    assert isinstance(seq, KittiSequence)
    assert len(seq) == 4
    cam = seq.camera
    assert (cam.fx, cam.fy, cam.cx, cam.cy) == (FX, FX, CX, CY)
    assert (cam.width, cam.height) == SIZE
    assert cam.baseline_m == pytest.approx(BASELINE, abs=1e-12)
    np.testing.assert_array_equal(seq.timestamps_ns, [0, 100_000_000, 200_000_000, 300_000_000])
    frame = seq[2]
    assert frame.left.shape == (SIZE[1], SIZE[0]) and frame.left.dtype == np.uint8
    assert frame.t_ns == 200_000_000
    assert not np.array_equal(frame.left, frame.right)
    gt = seq.groundtruth()
    assert gt.num_poses == 4
    np.testing.assert_allclose(gt.positions_xyz[:, 2], [0.0, 0.5, 1.0, 1.5])
    np.testing.assert_allclose(gt.timestamps, [0.0, 0.1, 0.2, 0.3])


def test_odometry_colour_pair_uses_p2_p3(tmp_path):
    seq_dir = make_odometry(tmp_path)
    names = [f"{i:06d}.png" for i in range(4)]
    _write_images(seq_dir / "image_2", names, 2)
    _write_images(seq_dir / "image_3", names, 3)
    seq = KittiSequence(seq_dir, color=True)
    assert seq.camera.baseline_m == pytest.approx(0.5, abs=1e-9)  # 0.56 - 0.06


def test_odometry_without_poses_has_no_groundtruth(tmp_path):
    seq = KittiSequence(make_odometry(tmp_path, poses=False))
    assert seq.groundtruth_path is None
    with pytest.raises(DatasetError, match="no ground truth"):
        seq.groundtruth()


def test_raw_drive_with_calibration_one_folder_up(tmp_path):
    drive = make_raw(tmp_path)
    assert kitti_layout(drive) == "raw"
    seq = open_dataset(drive)
    assert isinstance(seq, KittiSequence) and len(seq) == 4
    assert seq.calibration_path == drive.parent / "calib_cam_to_cam.txt"
    assert seq.camera.baseline_m == pytest.approx(BASELINE, abs=1e-12)
    t0 = np.datetime64("2011-09-26T13:02:25.007", "ns").astype(np.int64)
    assert seq.timestamps_ns[0] == t0
    assert seq.timestamps_ns[1] - t0 == 100_000_000
    assert seq.groundtruth_path is None


def test_raw_drive_with_calibration_inside(tmp_path):
    seq = KittiSequence(make_raw(tmp_path, calib_in_parent=False))
    assert seq.calibration_path.parent.name.endswith("_sync")


def _replace_line(path: Path, key: str, line: str | None) -> None:
    kept = [ln for ln in path.read_text().splitlines() if not ln.startswith(f"{key}:")]
    path.write_text("\n".join(kept + ([line] if line is not None else [])) + "\n")


@pytest.mark.parametrize(
    ("key", "line", "message"),
    [
        ("P1", None, "missing key 'P1'"),
        ("P1", "P1: 1 2 3", "'P1' must have 12 numbers, got 3"),
        ("P1", "P1: " + " ".join(["x"] * 12), "'P1' must be a list of numbers"),
        (
            "P1",
            "P1: " + _projection(BASELINE).replace("7.000000000000e+02", "nan", 1),
            "'P1' contains NaN or Inf",
        ),
        ("P1", "P1: " + _projection(-BASELINE), "to the right"),
        (
            "P1",
            "P1: " + _projection(BASELINE).replace("3.150000000000e+01", "40", 1),
            "different intrinsics",
        ),
        ("P0", "P0: " + " ".join(["0"] * 12), "'P0': not a rectified projection"),
        ("P0", "P0 " + _projection(0.0), "line 5: expected 'KEY: values'"),
    ],
)
def test_bad_odometry_calibration_names_file_and_key(tmp_path, key, line, message):
    seq_dir = make_odometry(tmp_path)
    _replace_line(seq_dir / "calib.txt", key, line)
    with pytest.raises(CalibrationError, match=message) as info:
        KittiSequence(seq_dir)
    assert str(seq_dir / "calib.txt") in str(info.value)


def test_duplicate_calibration_key_is_refused(tmp_path):
    seq_dir = make_odometry(tmp_path)
    with (seq_dir / "calib.txt").open("a") as handle:
        handle.write(f"P1: {_projection(0.3)}\n")
    with pytest.raises(CalibrationError, match="key 'P1' given twice"):
        KittiSequence(seq_dir)


def test_bad_times_files(tmp_path):
    seq_dir = make_odometry(tmp_path)
    (seq_dir / "times.txt").write_text("0\n0.1\n0.2\n")
    with pytest.raises(DatasetError, match="3 timestamps for 4 images"):
        KittiSequence(seq_dir)
    (seq_dir / "times.txt").write_text("0\n0.1\n0.1\n0.3\n")
    with pytest.raises(DatasetError, match="not strictly increasing at line 3"):
        KittiSequence(seq_dir)
    (seq_dir / "times.txt").write_text("0\nzero\n0.2\n0.3\n")
    with pytest.raises(DatasetError, match="not a times file"):
        KittiSequence(seq_dir)
    (seq_dir / "times.txt").unlink()
    with pytest.raises(DatasetError, match="missing times file"):
        KittiSequence(seq_dir)


def test_bad_raw_timestamps_and_pairs(tmp_path):
    drive = make_raw(tmp_path)
    stamps = drive / "image_01" / "timestamps.txt"
    good = stamps.read_text()
    stamps.write_text(good.replace("13:02:25.107", "13:02:25.157"))  # 50 ms off its left image
    with pytest.raises(DatasetError, match="image 1: 50000000 ns from its left image"):
        KittiSequence(drive)
    stamps.write_text(good.replace("2011-09-26 13:02:25.207", "26/09/2011 13:02:25"))
    with pytest.raises(DatasetError, match=r"line 3: .* is not 'YYYY-MM-DD hh:mm:ss.fff'"):
        KittiSequence(drive)
    stamps.write_text(good)
    (drive / "image_01" / "data" / "0000000003.png").rename(
        drive / "image_01" / "data" / "0000000009.png"
    )
    with pytest.raises(DatasetError, match="names differ"):
        KittiSequence(drive)


def test_unrectified_raw_images_are_refused_with_the_reason(tmp_path):
    drive = make_raw(tmp_path)
    calib = drive.parent / "calib_cam_to_cam.txt"
    calib.write_text(
        calib.read_text()
        .replace("S_00: 1.392000e+03 5.120000e+02", f"S_00: {SIZE[0]} {SIZE[1]}")
        .replace(f"S_rect_00: {SIZE[0]} {SIZE[1]}", "S_rect_00: 1242 375")
    )
    with pytest.raises(DatasetError, match=r"unrectified .*_sync download"):
        KittiSequence(drive)


def test_image_of_another_size_names_the_file(tmp_path):
    from slslam import _core

    seq_dir = make_odometry(tmp_path)
    _core.write_image(str(seq_dir / "image_1" / "000002.png"), np.zeros((10, 20), np.uint8))
    seq = KittiSequence(seq_dir)
    with pytest.raises(DatasetError, match=r"000002\.png: image is 20x10"):
        seq[2]


def test_not_kitti(tmp_path):
    assert not is_kitti(tmp_path)
    with pytest.raises(DatasetError, match="not a KITTI sequence"):
        KittiSequence(tmp_path)


def test_shared_raw_drive_frames_calibration_and_timestamps():
    drive = shared_path("kitti_raw_2011_09_26_drive_0001")
    seq = open_dataset(drive)
    assert isinstance(seq, KittiSequence) and seq.layout == "raw"
    assert len(seq) == 108
    cam = seq.camera
    assert (cam.width, cam.height) == (1242, 375)
    assert cam.fx == pytest.approx(721.5377) and cam.fy == pytest.approx(721.5377)
    assert (cam.cx, cam.cy) == (pytest.approx(609.5593), pytest.approx(172.854))
    assert cam.baseline_m == pytest.approx(387.5744 / 721.5377, rel=1e-9)  # 0.5372 m
    # timestamps.txt read as UTC: the times of ORB-SLAM3's reference trajectory
    reference = np.loadtxt(drive / "reference_orbslam3_stereo.tum")
    np.testing.assert_allclose(seq.timestamps_ns * 1e-9, reference[:, 0], atol=1e-6, rtol=0)
    assert seq.timestamps_ns[0] == 1_317_042_145_967_790_592
    rate = (len(seq) - 1) / ((seq.timestamps_ns[-1] - seq.timestamps_ns[0]) * 1e-9)
    assert 9.5 < rate < 10.5
    frame = seq[50]
    assert frame.left.shape == (375, 1242) and frame.right.shape == (375, 1242)


def test_default_configuration_tracks_the_shared_drive_at_the_right_scale(tmp_path):
    """The library's default configuration on real KITTI (1242 x 375, 0.54 m baseline, 10 Hz):
    every frame posed, one map, and the path within 2 % of ORB-SLAM3's, run beside it."""
    from slslam.config import default_config
    from slslam.datasets import read_trajectory
    from slslam.tracking import run_sequence

    drive = shared_path("kitti_raw_2011_09_26_drive_0001")
    reference = drive / "reference_orbslam3_stereo.tum"
    summary = run_sequence(drive, tmp_path / "run", default_config(), progress=False)
    m = summary.metrics
    assert m["frames"] == 108 and m["tracked_frames"] == 108, m["states"]
    assert m["maps"] == 1
    # the options counted in frames at KITTI's 10 Hz: the same times as at the 20 Hz they are
    # given at (tracking.reference_rate_hz)
    assert m["rig_adapted"]["frame_rate_hz"] == pytest.approx(9.7, rel=0.01)  # its time stamps
    assert m["rig_adapted"]["keyframe_max_frames"] == 10
    assert m["rig_adapted"]["recently_lost_frames"] == 5
    estimate = read_trajectory(tmp_path / "run" / "trajectory.tum", "tum")
    ours = np.linalg.norm(np.diff(estimate.positions_xyz, axis=0), axis=1).sum()
    ref = read_trajectory(reference, "tum")
    theirs = np.linalg.norm(np.diff(ref.positions_xyz, axis=0), axis=1).sum()
    assert abs(ours - theirs) <= 0.02 * theirs, (ours, theirs)
    # times written as exact fixed-point seconds: the drive's own nanoseconds, no float noise
    stamps = KittiSequence(drive).timestamps_ns
    for name in ("trajectory.tum", "trajectory_online.tum"):
        rows = (tmp_path / "run" / name).read_text().splitlines()
        assert [row.split()[0] for row in rows] == [tum_time(int(t)) for t in stamps]
    assert rows[0].startswith("1317042145.967790592 ")


def test_xfeat_keeps_the_scale_of_the_shared_drive(tmp_path):
    """XFeat + lines (its preset, tuned at 20 Hz on the simulator's 458 px rig) on KITTI's
    10 Hz, 721 px rig: with the preset's keyframe gap counted in frames it kept 44 % of the path;
    the counts follow the camera's rate and the pixel windows its focal length
    (tracking.reference_rate_hz, reference_focal_px), so it keeps the scale."""
    from evo.core import sync
    from evo.core.metrics import PoseRelation
    from evo.main_ape import ape

    from slslam.config import config_from_dict
    from slslam.datasets import read_trajectory
    from slslam.tracking import run_sequence

    drive = shared_path("kitti_raw_2011_09_26_drive_0001")
    config = config_from_dict({"features": {"point_frontend": "xfeat"}})
    m = run_sequence(drive, tmp_path / "run", config, progress=False).metrics
    assert m["tracked_frames"] == m["frames"] == 108 and m["maps"] == 1, m["states"]
    assert m["rig_adapted"]["keyframe_min_frames"] == 3  # the preset's 6 at 20 Hz
    estimate = read_trajectory(tmp_path / "run" / "trajectory.tum", "tum")
    reference = read_trajectory(drive / "reference_orbslam3_stereo.tum", "tum")
    theirs = np.linalg.norm(np.diff(reference.positions_xyz, axis=0), axis=1).sum()
    ours = np.linalg.norm(np.diff(estimate.positions_xyz, axis=0), axis=1).sum()
    assert abs(ours - theirs) <= 0.03 * theirs, (ours, theirs)
    ref, est = sync.associate_trajectories(reference, estimate, max_diff=0.01)
    rmse = ape(ref, est, PoseRelation.translation_part, align=True).stats["rmse"]
    assert rmse < 0.01 * theirs, rmse


def test_tum_time_is_exact():
    assert tum_time(1_317_042_145_967_790_592) == "1317042145.967790592"
    assert tum_time(5) == "0.000000005"
    assert tum_time(-1_500_000_000) == "-1.500000000"


def test_the_default_configuration_serves_the_simulated_rig_too(tmp_path):
    """The configuration of the KITTI test above, unchanged, on the simulator's rig (752 x 480,
    0.11 m baseline, 20 Hz, a dark roadway): every frame posed, one map, centimetre ATE."""
    from slslam.config import default_config
    from slslam.sim import SimOptions, Simulator
    from slslam.tracking import run_sequence

    seq = tmp_path / "loop"
    Simulator(SimOptions(preset="loop", frames=60, light=0.15, lidar=False)).write(
        seq, progress=False
    )
    m = run_sequence(seq, tmp_path / "run", default_config(), progress=False).metrics
    assert m["tracked_frames"] == m["frames"] == 60 and m["maps"] == 1
    assert m["ape"]["rmse"] < 0.05
    # the simulator's 20 Hz is the reference rate: the counts as configured
    assert m["rig_adapted"]["frame_rate_hz"] == pytest.approx(20.0)
    assert m["rig_adapted"]["keyframe_max_frames"] == default_config().tracking.keyframe_max_frames
