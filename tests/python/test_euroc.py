import numpy as np
import pytest

from slslam import _core
from slslam.datasets import EurocSequence, find_mav0, is_euroc, read_trajectory
from slslam.errors import DatasetError
from slslam.eval import load_groundtruth

from conftest import shared_path


def test_synthetic_sequence_reads_lazily_in_time_order(make_euroc):
    root = make_euroc(n=4)
    seq = EurocSequence(root)
    assert len(seq) == 4
    assert np.all(np.diff(seq.timestamps_ns) > 0)
    frames = list(seq)
    assert [f.index for f in frames] == [0, 1, 2, 3]
    assert [f.t_ns for f in frames] == seq.timestamps_ns.tolist()
    assert frames[0].left.shape == (48, 64) and frames[0].left.dtype == np.uint8
    assert seq[-1].t_ns == seq.timestamps_ns[-1]
    with pytest.raises(IndexError):
        seq[4]
    # mav0 itself is accepted too
    assert len(EurocSequence(root / "mav0")) == 4
    assert seq.camera.baseline_m == pytest.approx(0.11, abs=1e-9)


def test_raw_images_are_returned_unchanged_without_rectification(make_euroc):
    root = make_euroc(n=1)
    raw = EurocSequence(root, rectify=False)[0]
    on_disk = _core.read_gray_image(str(root / "mav0" / "cam0" / "data" / f"{raw.t_ns}.png"))
    np.testing.assert_array_equal(raw.left, on_disk)


def test_not_an_euroc_folder(tmp_path):
    (tmp_path / "images").mkdir()
    assert not is_euroc(tmp_path)
    with pytest.raises(DatasetError, match=r"not a EuRoC ASL folder: expected mav0/cam0/data.csv"):
        EurocSequence(tmp_path)
    with pytest.raises(DatasetError, match="dataset folder not found"):
        find_mav0(tmp_path / "missing")


def test_mismatched_stereo_timestamps(make_euroc):
    left = [1_000_000_000 + 50_000_000 * i for i in range(5)]
    right = list(left)
    right[2] += 7_000_000  # 7 ms off: not the same exposure
    root = make_euroc(n=5, right_stamps=right)
    with pytest.raises(
        DatasetError,
        match=r"cam1/data.csv: stereo timestamps do not pair up.*"
        r"1 left images with no right image within 0 ns.*t = 1100000000 ns",
    ):
        EurocSequence(root)
    # A tolerance that covers the offset accepts the pair.
    assert len(EurocSequence(root, stereo_tolerance_ns=10_000_000)) == 5


def test_extra_frames_outside_the_common_span_are_ignored(make_euroc, caplog):
    left = [1_000_000_000 + 50_000_000 * i for i in range(5)]
    root = make_euroc(n=5, right_stamps=[*left, left[-1] + 50_000_000])
    assert len(EurocSequence(root)) == 5
    assert "1 of 6 images lie outside the other camera's time span" in caplog.text


def test_missing_and_unreadable_images(make_euroc):
    root = make_euroc(n=3)
    images = sorted((root / "mav0" / "cam1" / "data").glob("*.png"))
    images[1].unlink()
    with pytest.raises(DatasetError, match=rf"{images[1]}: image file not found \(1 of 3"):
        EurocSequence(root)
    images[1].write_bytes(b"this is not a png")
    seq = EurocSequence(root)
    with pytest.raises(DatasetError, match=rf"{images[1]}.*unreadable"):
        seq[1]


def test_wrong_image_size_names_the_file(make_euroc):
    root = make_euroc(n=2, size=(80, 48))  # calibration says 64 x 48
    seq = EurocSequence(root)
    with pytest.raises(DatasetError, match=r"image is 80x48 but the calibration is for 64x48"):
        seq[0]


def test_non_monotonic_index(make_euroc):
    root = make_euroc(n=3)
    csv = root / "mav0" / "cam0" / "data.csv"
    lines = csv.read_text().splitlines()
    lines[2], lines[3] = lines[3], lines[2]
    csv.write_text("\n".join(lines) + "\n")
    with pytest.raises(DatasetError, match="timestamps not strictly increasing at image 2"):
        EurocSequence(root)


def test_real_excerpt_pairs_95_frames(euroc_micro):
    seq = EurocSequence(euroc_micro)
    assert len(seq) == 95
    cam = seq.camera
    assert (cam.width, cam.height) == (752, 480)
    assert cam.baseline_m == pytest.approx(0.110, abs=0.001)
    imu = seq.imu()
    assert imu["acc"].shape[1] == 3 and len(imu["t_ns"]) > 20_000
    # Standing still: the accelerometer measures gravity only.
    assert np.linalg.norm(imu["acc"][:200].mean(axis=0)) == pytest.approx(9.81, abs=0.2)


def _row_errors(left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertical and horizontal offsets of ORB matches between two images."""
    options = _core.OrbOptions()
    options.max_features = 1500
    uv_l, _, d_l = _core.extract_orb(left, options)
    uv_r, _, d_r = _core.extract_orb(right, options)
    pairs = _core.match_descriptors(d_l, d_r)
    delta = uv_l[pairs[:, 0]] - uv_r[pairs[:, 1]]
    return delta[:, 1], delta[:, 0]


def test_real_excerpt_rectified_rows_agree(euroc_micro):
    rectified = EurocSequence(euroc_micro)
    raw = EurocSequence(euroc_micro, rectify=False)
    dy_rect, dx_rect, dy_raw = [], [], []
    for i in range(0, 95, 10):
        dy, dx = _row_errors(rectified[i].left, rectified[i].right)
        dy_rect.append(dy)
        dx_rect.append(dx)
        dy_raw.append(_row_errors(raw[i].left, raw[i].right)[0])
    dy_rect, dx_rect, dy_raw = (np.concatenate(a) for a in (dy_rect, dx_rect, dy_raw))
    # Outlier matches exist; keep those with a plausible disparity (0.5 m .. infinity at fx b).
    plausible = (dx_rect > 0) & (dx_rect < 100)
    assert plausible.sum() > 500
    median_dy = np.median(np.abs(dy_rect[plausible]))
    assert median_dy < 0.5, f"median |dy| after rectification {median_dy:.3f} px"
    # The raw pair is visibly off (rotation between the cameras), so the check can fail.
    assert np.median(np.abs(dy_raw)) > 2 * median_dy


def test_body_groundtruth_converted_to_left_camera():
    """EuRoC body GT @ cam0 T_BS reproduces the published left-camera GT positions."""
    body_csv = shared_path("trajectories", "V102_groundtruth.csv")
    cam0_yaml = shared_path("euroc_calib", "euroc_cam0_sensor.yaml")
    leftcam = read_trajectory(shared_path("euroc_groundtruth_leftcam", "V102_GT.txt"), "euroc")
    gt_cam = load_groundtruth(body_csv, gt_body_to_cam=cam0_yaml)
    gt_body = load_groundtruth(body_csv)
    index = np.searchsorted(gt_cam.timestamps, leftcam.timestamps)
    ok = (index < gt_cam.num_poses) & (
        np.abs(gt_cam.timestamps[np.minimum(index, gt_cam.num_poses - 1)] - leftcam.timestamps)
        < 1e-4
    )
    assert ok.sum() > 1000
    err_cam = np.linalg.norm(gt_cam.positions_xyz[index[ok]] - leftcam.positions_xyz[ok], axis=1)
    err_body = np.linalg.norm(gt_body.positions_xyz[index[ok]] - leftcam.positions_xyz[ok], axis=1)
    assert err_cam.max() < 2e-4
    assert err_body.min() > 0.03  # the lever arm of ~7 cm is visible without the conversion
