"""benchmarks/kitti.py: the published KITTI numbers file, the table that puts them beside a run
(a made-up results dict, no SLAM run), and the KITTI devkit's relative errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slslam.datasets import read_trajectory
from slslam.errors import InputError

from conftest import load_benchmark, shared_path


@pytest.fixture(scope="module")
def kitti_bench():
    yield from load_benchmark("kitti.py")


# -- the published numbers file -----------------------------------------------------------------
def test_published_file_structure(kitti_bench):
    published = kitti_bench.load_published(kitti_bench.PUBLISHED)
    assert published, "no source"
    for name, entry in published.items():
        assert entry["label"].strip(), name
        assert entry["citation"].strip(), name
        assert set(entry["values"]) <= set(kitti_bench.SEQUENCES), name
        for seq, metrics in entry["values"].items():
            assert set(metrics) <= set(kitti_bench.PUBLISHED_METRICS), (name, seq)
            for value in metrics.values():
                assert isinstance(value, int | float) and math.isfinite(value), (name, seq)
    assert kitti_bench.SEQUENCES == tuple(f"{i:02d}" for i in range(11))


def test_published_file_holds_the_orbslam2_stereo_table(kitti_bench):
    """ORB-SLAM2's Table I (stereo): all eleven training sequences, the three metrics each."""
    entry = kitti_bench.load_published(kitti_bench.PUBLISHED)["orbslam2_paper"]
    values = entry["values"]
    assert list(values) == [f"{i:02d}" for i in range(11)]
    assert all(set(v) == {"t_rel", "r_rel", "t_abs"} for v in values.values())
    assert values["00"] == {"t_rel": 0.70, "r_rel": 0.25, "t_abs": 1.3}
    assert values["01"] == {"t_rel": 1.39, "r_rel": 0.21, "t_abs": 10.4}
    assert values["10"] == {"t_rel": 0.60, "r_rel": 0.27, "t_abs": 1.0}
    assert "10.1109/TRO.2017.2705103" in entry["citation"]
    assert "Table I" in entry["citation"]


@pytest.mark.parametrize(
    ("text", "key"),
    [
        ("sources: {}\n", "sources"),
        ("sources:\n  a: {label: A, values: {}}\n", "sources.a: needs a 'citation'"),
        (
            "sources:\n  a: {label: A, citation: x, values: {'11': {t_rel: 1.0}}}\n",
            "sources.a.values.11",
        ),
        ("sources:\n  a: {label: A, citation: x, values: {00: {t_rel: 1.0}}}\n", "values.0"),
        (
            "sources:\n  a: {label: A, citation: x, values: {'00': {ate: 1.0}}}\n",
            "values.00.ate: unknown metric",
        ),
        ("sources:\n  a: {label: A, citation: x, values: {'00': {t_rel: .nan}}}\n", "t_rel"),
        ("sources:\n  a: {label: A, citation: x, values: {'00': {t_rel: fast}}}\n", "t_rel"),
        ("sources: [\n", "cannot read"),
    ],
)
def test_bad_published_file_names_file_and_key(kitti_bench, tmp_path, text, key):
    path = tmp_path / "published.yaml"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        kitti_bench.load_published(path)
    assert str(path) in str(info.value) and key in str(info.value)


def test_bad_published_file_stops_the_script_before_any_run(kitti_bench, tmp_path):
    path = tmp_path / "published.yaml"
    path.write_text("sources: {}\n")
    with pytest.raises(SystemExit) as info:
        kitti_bench.main(["--published", str(path), "--sequences", str(tmp_path / "none")])
    assert info.value.code == 2


# -- the table ----------------------------------------------------------------------------------
def _row(**extra) -> dict:
    row = {
        "frames": 4541,
        "posed": 4541,
        "maps": 1,
        "frontend": "orb",
        "lines": True,
        "path_m": 3721.4,
        "reference_path_m": 3724.2,
        "path_error_percent": -0.08,
        "ate_m": 2.3456,
        "ate_percent_of_path": 0.063,
        "t_rel_percent": 0.912,
        "r_rel_deg_per_100m": 0.331,
        "fps": 11.2,
    }
    row.update(extra)
    return row


def _cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def test_table_puts_the_published_numbers_beside_a_run(kitti_bench):
    published = kitti_bench.load_published(kitti_bench.PUBLISHED)
    results = {
        "00": {"orb_lines": _row()},
        "kitti_raw_2011_09_26_drive_0001": {"orb_lines": _row(t_rel_percent=None)},
    }
    lines = kitti_bench.table(results, published).splitlines()
    head = _cells(lines[0])
    label = published["orbslam2_paper"]["label"]
    # slslam's own t_rel / r_rel / ATE columns and the paper's, one metric per column
    for title in ("ATE [m]", "t_rel [%]", "r_rel [deg/100 m]"):
        assert head.count(title) == 1
    for title in ("t_rel [%]", "r_rel [deg/100 m]", "t_abs [m]"):
        assert f"{label} {title}" in head
    assert len(set(head)) == len(head)
    rows = {(c[0], c[1]): dict(zip(head, c, strict=True)) for c in map(_cells, lines[2:])}
    run = rows[("00", "orb_lines (orb + lines)")]
    assert run["t_rel [%]"] == "0.91" and run["r_rel [deg/100 m]"] == "0.33"
    assert run["ATE [m]"] == "2.346"
    assert run[f"{label} t_rel [%]"] == "0.70"
    assert run[f"{label} r_rel [deg/100 m]"] == "0.25"
    assert run[f"{label} t_abs [m]"] == "1.3"
    # a raw drive is not a KITTI odometry sequence: no published numbers on its row
    raw = rows[("kitti_raw_2011_09_26_drive_0001", "orb_lines (orb + lines)")]
    assert raw["t_rel [%]"] == "-" and raw[f"{label} t_rel [%]"] == "-"
    # the published sequences not run are listed, with "-" in slslam's columns
    for seq in [f"{i:02d}" for i in range(1, 11)]:
        row = rows[(seq, "-")]
        assert row["ATE [m]"] == "-" and row["t_rel [%]"] == "-"
        assert row[f"{label} t_rel [%]"] != "-"
    assert rows[("01", "-")][f"{label} t_abs [m]"] == "10.4"
    assert len(lines) == 2 + 2 + 10


def test_table_without_published_numbers_is_slslam_alone(kitti_bench):
    lines = kitti_bench.table({"00": {"orb": _row(lines=False)}}).splitlines()
    assert len(lines) == 3 and len(_cells(lines[0])) == 12
    assert _cells(lines[2])[:2] == ["00", "orb (orb)"]


def test_notes_cite_each_source_and_warn_on_partial_runs(kitti_bench):
    published = kitti_bench.load_published(kitti_bench.PUBLISHED)
    notes = kitti_bench.table_notes(published, frames=200)
    assert any("10.1109/TRO.2017.2705103" in n for n in notes)
    assert "not comparable" in notes[-1]


# -- the KITTI devkit's relative errors ---------------------------------------------------------
def _straight(n: int) -> np.ndarray:
    """n poses 1 m apart along the camera's z axis (KITTI's forward), identity rotations."""
    poses = np.repeat(np.eye(4)[None], n, axis=0)
    poses[:, 2, 3] = np.arange(n, dtype=float)
    return poses


def _yaw(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _expected_mean(n: int, per_segment) -> tuple[float, int]:
    """Mean of per_segment(length) over the devkit's segments of _straight(n): starts every 10th
    frame, the segment of length L ends L + 1 frames later (the first distance above L)."""
    values = [
        per_segment(length)
        for first in range(0, n, 10)
        for length in range(100, 900, 100)
        if first + length + 1 < n
    ]
    return float(np.mean(values)), len(values)


def test_relative_errors_of_a_scaled_straight_drive(kitti_bench):
    gt = _straight(1000)
    est = gt.copy()
    est[:, :3, 3] *= 1.01  # 1 % too long: the error over a segment is 1 % of its chord
    result = kitti_bench.kitti_relative_errors(gt, est)
    mean, count = _expected_mean(1000, lambda length: 0.01 * (length + 1) / length)
    assert result["segments"] == count
    assert result["t_rel_percent"] == pytest.approx(100 * mean, rel=1e-9)
    assert result["r_rel_deg_per_100m"] == pytest.approx(0.0, abs=1e-6)


def test_relative_errors_of_a_rotation_drift(kitti_bench):
    """A yaw drift of eps per frame: a segment's rotation error is eps * frames / length."""
    eps = 1e-4
    gt = _straight(1000)
    est = gt.copy()
    for i in range(len(est)):
        est[i, :3, :3] = _yaw(eps * i)
    result = kitti_bench.kitti_relative_errors(gt, est)
    mean, _ = _expected_mean(1000, lambda length: eps * (length + 1) / length)
    assert result["r_rel_deg_per_100m"] == pytest.approx(100 * math.degrees(mean), rel=1e-6)


def test_relative_errors_need_100_m(kitti_bench):
    result = kitti_bench.kitti_relative_errors(_straight(100), _straight(100))
    assert result == {"t_rel_percent": None, "r_rel_deg_per_100m": None, "segments": 0}
    with pytest.raises(InputError):
        kitti_bench.kitti_relative_errors(_straight(100), _straight(99))


def test_relative_errors_on_kitti_00_ignore_the_estimates_world(kitti_bench):
    """KITTI 00's ground truth (4,541 poses) against itself seen from another world frame: the
    metric is relative, so zero; every 100-800 m segment of the sequence is scored."""
    gt_path = shared_path("trajectories", "KITTI_00_gt.txt")
    gt = np.array(read_trajectory(gt_path, "kitti").poses_se3)
    world = np.eye(4)
    world[:3, :3] = _yaw(0.7)
    world[:3, 3] = [12.0, -3.0, 40.0]
    result = kitti_bench.kitti_relative_errors(gt, world @ gt)
    assert result["t_rel_percent"] == pytest.approx(0.0, abs=1e-9)
    assert result["r_rel_deg_per_100m"] == pytest.approx(0.0, abs=1e-5)
    assert 3000 < result["segments"] <= 8 * len(range(0, len(gt), 10))


def test_run_with_an_unposed_frame_gets_no_relative_errors(kitti_bench):
    from evo.core.trajectory import PoseTrajectory3D

    gt_poses = _straight(300)
    stamps = np.arange(300) * 0.1
    gt = PoseTrajectory3D(poses_se3=list(gt_poses), timestamps=stamps)
    full = kitti_bench.relative_errors_of_run(gt, gt, 300)
    assert full["segments"] > 0 and full["t_rel_percent"] == pytest.approx(0.0, abs=1e-9)
    keep = np.ones(300, dtype=bool)
    keep[150] = False
    gappy = PoseTrajectory3D(poses_se3=list(gt_poses[keep]), timestamps=stamps[keep])
    assert kitti_bench.relative_errors_of_run(gappy, gt, 300)["t_rel_percent"] is None
    assert kitti_bench.relative_errors_of_run(None, gt, 300)["segments"] is None
