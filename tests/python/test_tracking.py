"""Stereo point-line tracking end to end: ``slslam.Tracker`` and ``slslam run`` on a simulated
roadway generated here and on the real EuRoC excerpt, reproducibility, bad input, runs that fail
midway."""

from __future__ import annotations

import dataclasses
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from slslam import _core
from slslam.config import Config, load_config
from slslam.datasets import EurocSequence
from slslam.errors import DatasetError, InputError
from slslam.features.orb import Orb
from slslam.sim import SimOptions, Simulator
from slslam.tracking import MapStats, Tracker, run_sequence

from conftest import SHARED_DATA, shared_path

REAL_MODEL = SHARED_DATA.parent / "models" / "superpoint_v1" / "superpoint_v1.onnx"
V101_GT = ("euroc_groundtruth_leftcam", "V101_GT.txt")


def config(frontend: str = "orb", lines: bool = True, model: str | None = None) -> Config:
    """A config with the given point front end (ORB unless asked) and lines on or off."""
    base = Config()
    sp = dataclasses.replace(base.features.superpoint, model_path=model)
    features = dataclasses.replace(base.features, point_frontend=frontend, superpoint=sp)
    tracking = dataclasses.replace(base.tracking, use_lines=lines)
    return dataclasses.replace(base, features=features, tracking=tracking)


@pytest.fixture(scope="module")
def sim_loop(tmp_path_factory) -> Path:
    """80 frames (4 s, 3 m) of the simulated shaft-bottom loop at full light, written as EuRoC."""
    out = tmp_path_factory.mktemp("sim") / "loop"
    Simulator(SimOptions(preset="loop", frames=80, lidar=False)).write(out, progress=False)
    return out


def test_run_on_the_simulated_loop_tracks_every_frame_and_writes_every_file(sim_loop, tmp_path):
    summary = run_sequence(sim_loop, tmp_path, config("orb", lines=True), progress=False)
    m = summary.metrics
    assert m["frames"] == 80
    assert m["tracked_ratio"] == 1.0
    # Measured 1.3 cm over the 3 m (ORB + lines); a broken pose chain is metres off.
    assert m["ape"]["rmse"] < 0.03
    assert m["keyframes"] >= 2 and m["map_points"] > 500 and m["map_lines"] > 20
    lm = m["local_mapping"]
    assert lm["keyframes_processed"] >= 2
    # The local BAs' counters: steps within the caps (5 + 10 a keyframe), rejected ones among
    # them, the solves' time within local mapping's.
    assert 0 < lm["local_ba_iterations"] <= 15 * lm["keyframes_processed"]
    assert 0 <= lm["local_ba_rejected_steps"] < lm["local_ba_iterations"]
    assert 0.0 < lm["local_ba_solve_ms"] < lm["local_mapping_ms"]
    # Every input frame is in the TUM file, time-ordered, with finite poses.
    traj = np.loadtxt(tmp_path / "trajectory.tum")
    assert traj.shape == (80, 8) and np.all(np.isfinite(traj)) and np.all(np.diff(traj[:, 0]) > 0)
    assert len((tmp_path / "frames.csv").read_text().splitlines()) == 81
    header = (tmp_path / "map.ply").read_text().split("end_header")[0]
    assert f"element vertex {m['map_points'] + 2 * m['map_lines']}" in header
    assert f"element edge {m['map_lines']}" in header
    assert json.loads((tmp_path / "metrics.json").read_text())["ape"]["rmse"] == m["ape"]["rmse"]
    assert (tmp_path / "ape.png").stat().st_size > 1000
    assert load_config(tmp_path / "config.yaml").tracking.use_lines is True


def test_the_dumped_config_is_the_one_that_ran(sim_loop, tmp_path, monkeypatch):
    """SuperPoint requested without weights falls back to ORB: config.yaml says ORB ran (and
    why, in its header), names the vocabulary relocalisation loaded, and still loads."""
    monkeypatch.delenv("SLSLAM_SUPERPOINT_MODEL", raising=False)
    run_sequence(sim_loop, tmp_path, config("superpoint", model=None), max_frames=5, progress=False)
    text = (tmp_path / "config.yaml").read_text()
    assert text.startswith("# slslam ")
    # The commit the core was built from (a git checkout here; "unknown" outside one).
    assert re.search(r"commit ([0-9a-f]{12}(-dirty)?|unknown)\)", text.splitlines()[0])
    assert f"commit {_core.__git_commit__})" in text.splitlines()[0]
    assert "features.point_frontend: superpoint requested, orb ran" in text
    dumped = load_config(tmp_path / "config.yaml")
    assert dumped.features.point_frontend == "orb"
    assert dumped.tracking.vocabulary_path.endswith("orb_vocabulary.slvoc")


def test_sequential_mode_is_reproducible_bit_for_bit(sim_loop):
    sequence = EurocSequence(sim_loop)
    runs = []
    for _ in range(2):
        with Tracker(sequence.camera, config("orb", lines=True)) as tracker:
            for i in range(30):
                f = sequence[i]
                tracker.track(f.left, f.right, f.t_ns * 1e-9)
            runs.append(tracker.trajectory()[1])
    assert np.array_equal(runs[0], runs[1])


def test_orb_points_only_on_the_real_euroc_excerpt(tmp_path):
    """The camera stands still in the excerpt (< 3.3 mm, 0.27 deg over the ground truth): the
    estimate must stay within millimetres of it (measured ATE 3.7 mm)."""
    data = shared_path("euroc_v101_micro")
    gt = shared_path(*V101_GT)
    summary = run_sequence(
        data, tmp_path, config("orb", lines=False), progress=False, groundtruth=gt
    )
    assert summary.metrics["tracked_ratio"] == 1.0
    assert summary.metrics["ape"]["rmse"] < 0.01


def test_superpoint_with_lines_on_the_real_euroc_excerpt(tmp_path):
    """The real path: SuperPoint weights through onnxruntime, LSD + LBD, Ceres."""
    data = shared_path("euroc_v101_micro")
    gt = shared_path(*V101_GT)
    model = os.environ.get("SLSLAM_SUPERPOINT_MODEL") or (
        str(REAL_MODEL) if REAL_MODEL.is_file() else None
    )
    if model is None:
        pytest.skip("no SuperPoint weights ($SLSLAM_SUPERPOINT_MODEL or ../shared/models)")
    summary = run_sequence(
        data,
        tmp_path,
        config("superpoint", lines=True, model=model),
        max_frames=40,
        progress=False,
        groundtruth=gt,
    )
    m = summary.metrics
    assert m["frontend"] == "SuperPoint"
    assert m["tracked_ratio"] == 1.0
    assert m["ape"]["rmse"] < 0.01
    assert m["map_lines"] > 0


def test_bad_frames_raise_clear_errors(sim_loop):
    sequence = EurocSequence(sim_loop)
    f = sequence[0]
    with Tracker(sequence.camera, config("orb")) as tracker:
        with pytest.raises(InputError, match="differ from the calibration"):
            tracker.track(f.left[:100], f.right[:100], 0.0)
        with pytest.raises(InputError, match="not finite"):
            tracker.track(f.left, f.right, float("nan"))
        assert tracker.track(f.left, f.right, 1.0).state == "OK"
        with pytest.raises(InputError, match="does not increase"):
            tracker.track(f.left, f.right, 1.0)


def test_black_frames_are_states_not_exceptions(sim_loop):
    """A black first frame leaves the tracker uninitialised; a short blackout later (lamp out)
    is RECENTLY_LOST (a prediction with a decaying velocity), then tracking resumes in the same
    map; every frame gets a finite pose."""
    sequence = EurocSequence(sim_loop)
    black = np.zeros_like(sequence[0].left)
    states = []
    with Tracker(sequence.camera, config("orb", lines=True)) as tracker:
        for i in range(30):
            f = sequence[i]
            dark = i == 0 or 12 <= i < 15
            left, right = (black, black) if dark else (f.left, f.right)
            result = tracker.track(left, right, f.t_ns * 1e-9)
            assert np.all(np.isfinite(result.T_world_cam))
            states.append(result.state)
        assert tracker.map().maps == 1
    assert states[0] == "NOT_INITIALIZED"
    assert states[1:12] == ["OK"] * 11
    assert states[12:15] == ["RECENTLY_LOST"] * 3
    assert set(states[15:]) == {"OK"}


@pytest.mark.parametrize(
    "case",
    [
        # A half turn on the spot in 3 s (2 rad/s peak, 6 degrees per frame), past bare walls at
        # light 0.5; the robot then drives on looking backwards. (A full turn in 3 s, 4 rad/s,
        # loses about 20 frames mid-turn: measured, not asserted.)
        {"spin_at_s": 4.0, "spin_duration_s": 3.0, "spin_deg": 180.0, "light": 0.5, "frames": 180},
    ],
    ids=["turn_on_the_spot"],
)
def test_hard_cases_end_in_one_map_with_every_lit_frame_posed(case, tmp_path):
    """Issue 13's hard cases, simulated end to end: the tracker holds on through a turn on the
    spot in one map; frames without an estimate go to lost_predictions.tum, never to
    trajectory.tum. (The blackout: the test below.)"""
    data = tmp_path / "seq"
    Simulator(SimOptions(preset="junction", lidar=False, **case)).write(data, progress=False)
    summary = run_sequence(data, tmp_path / "run", config("orb", lines=True), progress=False)
    m = summary.metrics
    lit = [r for r in summary.results if r.counts.keypoints > 50]
    assert sum(r.tracked for r in lit) >= len(lit) - 1
    assert m["maps"] == 1
    # Path about 3-5 m; a pose chain broken at the hard moment is tens of centimetres off.
    assert m["ape"]["rmse"] < 0.1
    traj = np.loadtxt(tmp_path / "run" / "trajectory.tum").reshape(-1, 8)
    lost = np.loadtxt(tmp_path / "run" / "lost_predictions.tum").reshape(-1, 8)
    assert len(traj) == sum(r.tracked for r in summary.results)
    assert len(traj) + len(lost) == m["frames"]


def test_low_texture_stretch_in_the_dark_starts_and_holds_a_map_with_the_fallback():
    """Issue 13's low-texture case, end to end and from a cold start: 80 frames of the hard
    junction's bare stretch (frames 380-459 of the 600-frame run: light 0.15, dust, flicker;
    15-50 weighted inliers a frame there in the full run), rendered directly. With the per-cell
    fallback a map starts on the first frame and holds (measured: 3 RECENTLY_LOST frames, 0.22 m
    off after 3.2 m from a cold start here); with plain ORB detection most frames are not
    tracked (measured: no map starts on the smoothed pair, tracking.denoise_above_noise; with the
    pair smoothed for stereo matching only, maps started and were lost, 21 % tracked)."""
    from slslam.datasets.euroc import RectifiedStereoCamera

    options = SimOptions(
        preset="junction",
        light=0.15,
        dust=True,
        flicker=True,
        blackout=True,
        frames=600,
        lidar=False,
    )
    sim = Simulator(options)
    cam = sim.camera
    camera = RectifiedStereoCamera(
        cam.fx, cam.fx, cam.cx, cam.cy, cam.width, cam.height, cam.baseline_m, cam.T_body_cam0
    )
    frames = range(380, 460)
    pairs = [sim.render_stereo(i)[:2] for i in frames]
    times = [i / options.rate_hz for i in frames]
    T_world_cam = sim.trajectory.pose(np.array(times)) @ cam.T_body_cam0

    def run(fallback: bool) -> tuple[list, int]:
        base = config("orb", lines=True)
        features = dataclasses.replace(base.features, low_texture_fallback=fallback)
        with Tracker(camera, dataclasses.replace(base, features=features)) as tracker:
            results = [
                tracker.track(left, right, t) for (left, right), t in zip(pairs, times, strict=True)
            ]
            return results, tracker.map().maps

    results, maps = run(True)
    states = [r.state for r in results]
    tracked = np.array([r.tracked for r in results])
    assert maps == 1
    assert tracked[1:].mean() >= 0.95, " ".join(states)
    assert "LOST" not in states, " ".join(states)
    # Relative to the first frame; the path is about 3.2 m.
    est = np.array([np.linalg.inv(results[0].T_world_cam) @ r.T_world_cam for r in results])
    truth = np.linalg.inv(T_world_cam[0]) @ T_world_cam
    travelled = float(np.linalg.norm(truth[-1, :3, 3]))
    error = np.linalg.norm(est[:, :3, 3] - truth[:, :3, 3], axis=1)
    assert travelled > 2.5
    assert error[tracked].max() < 0.1 * travelled, error[tracked].max()
    plain, _plain_maps = run(False)
    plain_tracked = np.mean([r.tracked for r in plain])
    assert plain_tracked < 0.5, plain_tracked


def _relative_position_error(result_a, result_b, gt_by_time) -> tuple[float, float]:
    """(distance moved, error of the estimated relative position) from frame a to frame b [m]."""
    est = np.linalg.inv(result_a.T_world_cam) @ result_b.T_world_cam
    ga, gb = (gt_by_time[round(r.timestamp, 3)] for r in (result_a, result_b))
    truth = np.linalg.inv(ga) @ gb
    return float(np.linalg.norm(truth[:3, 3])), float(np.linalg.norm(est[:3, 3] - truth[:3, 3]))


def test_a_blackout_is_bridged_by_the_imu_and_reported_lost_without_it(tmp_path):
    """The headlamp out for 1 s at light 0.5 (frames 70-89 black, pure sensor noise), then on
    again, end to end through ``run_sequence``. With the simulator's IMU (imu0/, used by default)
    the black frames are INERTIAL: posed, in trajectory.tum, and close to the truth; camera only,
    they are lost (no estimate, in lost_predictions.tum). Both come back into the one map."""
    data = tmp_path / "seq"
    Simulator(
        SimOptions(preset="junction", lidar=False, blackout=True, light=0.5, frames=160)
    ).write(data, progress=False)
    gt = EurocSequence(data).groundtruth(frame="rectified")
    gt_by_time = {round(t, 3): T for t, T in zip(gt.timestamps, gt.poses_se3, strict=True)}

    summary = run_sequence(data, tmp_path / "imu", config("orb", lines=True), progress=False)
    m, results = summary.metrics, summary.results
    inertial = [i for i, r in enumerate(results) if r.state == "INERTIAL"]
    assert m["inertial_frames"] == len(inertial) >= 15
    assert m["lost_frames"] <= 1 and m["posed_ratio_after_init"] >= 0.99
    assert m["maps"] == 1 and m["ape"]["rmse"] < 0.1
    traj = np.loadtxt(tmp_path / "imu" / "trajectory.tum").reshape(-1, 8)
    assert len(traj) == sum(r.tracked for r in results)  # INERTIAL poses are estimates
    # Dead reckoning from the last tracked frame: about 1 m in 1 s, measured 1.4 cm off on the
    # 600-frame junction; a constant-velocity guess in a turn is tens of centimetres off.
    before = results[inertial[0] - 1]
    assert before.state == "OK"
    moved, error = _relative_position_error(before, results[inertial[-1]], gt_by_time)
    assert moved > 0.3 and error < 0.05, (moved, error)

    no_imu = dataclasses.replace(
        config("orb", lines=True),
        tracking=dataclasses.replace(
            config().tracking, imu=dataclasses.replace(config().tracking.imu, enabled=False)
        ),
    )
    camera_only = run_sequence(data, tmp_path / "camera", no_imu, progress=False)
    m = camera_only.metrics
    assert m["inertial_frames"] == 0 and m["lost_frames"] >= 15  # the black frames
    lost = np.loadtxt(tmp_path / "camera" / "lost_predictions.tum").reshape(-1, 8)
    assert len(lost) == m["lost_frames"] and m["maps"] == 1
    # Back where it truly is: 0.9 cm measured. A re-entry taken on line inliers and 15 of 112
    # point matches came back 23 cm off into the same map (0.055 m), without any loss reported.
    assert m["ape"]["rmse"] < 0.03


def _camera_only_blackout(tmp_path, **sim) -> dict:
    """Metrics of ORB + lines without the IMU on the 160-frame junction with a blackout."""
    data = tmp_path / "seq"
    Simulator(SimOptions(preset="junction", lidar=False, blackout=True, frames=160, **sim)).write(
        data, progress=False
    )
    base = config("orb", lines=True)
    no_imu = dataclasses.replace(
        base,
        tracking=dataclasses.replace(
            base.tracking, imu=dataclasses.replace(base.tracking.imu, enabled=False)
        ),
    )
    return run_sequence(data, tmp_path / "out", no_imu, progress=False).metrics


def test_a_camera_only_blackout_does_not_come_back_on_line_inliers(tmp_path):
    """The camera-only blackout of the test above with simulator seed 5: there the pose along the
    motion before the loss that gathered the most weighted inliers was wrong, carried by 32 line
    inliers and 13 of 108 point matches, and the run came back into the one map 0.49 m off (ATE)
    with no loss reported. A re-entry now needs a quarter of its point matches as inliers
    (tracking.lost_reentry_min_point_ratio); the right pose keeps 38-48 % on this junction."""
    m = _camera_only_blackout(tmp_path, light=0.5, seed=5)
    assert m["lost_frames"] >= 15 and m["maps"] == 1
    assert m["ape"]["rmse"] < 0.03  # 1.6 cm measured


def test_a_dark_camera_only_blackout_comes_back_where_two_frames_agree(tmp_path):
    """The blackout above in the dark (light 0.15, dust), seed 2, camera only. After it the poses
    along the motion before the loss reached the truth (1-9 cm off) frame after frame with 21-29
    weighted inliers, short of the bar of 30, until the frozen pose 1 m behind passed it on 30
    line inliers: one map, ATE 0.51 m, no loss reported. Two consecutive frames whose attempts
    agree (tracking.lost_reentry_confirm_m) now take the right pose with min_inliers."""
    m = _camera_only_blackout(tmp_path, light=0.15, dust=True, seed=2)
    assert m["lost_frames"] >= 15 and m["maps"] == 1
    assert m["ape"]["rmse"] < 0.06  # 2.6 cm measured


def test_relocalises_by_bag_of_words_after_a_blackout_and_a_jump_back(sim_loop):
    """The robot drives 80 frames, the lamp goes out for 15, and it is back at the start of the
    run (3 m behind, a kidnapping): the first lit frame is relocalised into the old map by bag of
    words, and the replayed frames get the poses of the first pass."""
    sequence = EurocSequence(sim_loop)
    black = np.zeros_like(sequence[0].left)
    order = list(range(80)) + [None] * 15 + list(range(30))
    first_pass: dict[int, np.ndarray] = {}
    replay = []
    with Tracker(sequence.camera, config("orb", lines=True)) as tracker:
        assert tracker.vocabulary is not None  # the shipped ORB vocabulary
        for k, i in enumerate(order):
            f = sequence[i if i is not None else 0]
            left, right = (f.left, f.right) if i is not None else (black, black)
            r = tracker.track(left, right, 100.0 + 0.05 * k)
            if k < 80:
                assert r.tracked
                first_pass[i] = r.T_world_cam
            elif i is not None:
                replay.append((i, r))
        maps = tracker.map()
    assert replay[0][1].state == "RELOCALISED"
    assert all(r.tracked for _, r in replay)
    assert maps.maps == 1 and maps.stats.relocalisations == 1
    # Typed counters; the dict-style access of 0.1 still answers, with a deprecation warning.
    assert isinstance(maps.stats, MapStats) and maps.stats.loop_events == ()
    with pytest.warns(DeprecationWarning, match="stats.key"):
        assert maps.stats["relocalisations"] == 1
    assert maps.stats.as_dict()["maps_started"] == maps.stats.maps_started
    # Measured: 6 mm median, 2 cm max on a 600-frame loop; a pose in a wrong place is metres off.
    errors = [np.linalg.norm(r.T_world_cam[:3, 3] - first_pass[i][:3, 3]) for i, r in replay]
    assert np.median(errors) < 0.03 and max(errors) < 0.1


def test_a_run_that_fails_midway_keeps_what_it_wrote(sim_loop, tmp_path):
    broken = tmp_path / "broken"
    subprocess.run(["cp", "-r", str(sim_loop), str(broken)], check=True)
    images = sorted((broken / "mav0" / "cam0" / "data").glob("*.png"))
    images[12].write_bytes(b"not a png")
    out = tmp_path / "out"
    with pytest.raises(Exception, match=images[12].name):
        run_sequence(broken, out, config("orb", lines=False), max_frames=20, progress=False)
    assert len(np.loadtxt(out / "trajectory.tum")) == 12
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["stopped_at_frame"] == 12 and "error" in metrics
    assert (out / "map.ply").is_file()


def test_bad_tracking_config_and_dataset_are_clear_errors(sim_loop, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("tracking:\n  min_inliers: 1\n")
    with pytest.raises(InputError, match="min_inliers"):
        Tracker(EurocSequence(sim_loop).camera, load_config(bad))
    with pytest.raises(DatasetError, match="not found"):
        run_sequence(tmp_path / "nowhere", tmp_path / "out")
    with pytest.raises(DatasetError, match="unknown dataset layout"):
        run_sequence(tmp_path, tmp_path / "out")


def test_cli_run_help_and_missing_dataset():
    cli = [sys.executable, "-m", "slslam", "run"]
    help_text = subprocess.run([*cli, "--help"], capture_output=True, text=True, check=True)
    assert "trajectory.tum" in help_text.stdout and "--groundtruth" in help_text.stdout
    missing = subprocess.run([*cli, "/nonexistent/seq"], capture_output=True, text=True)
    assert missing.returncode != 0
    assert "not found" in missing.stdout + missing.stderr
    assert "Traceback" not in missing.stdout + missing.stderr


def test_bad_imu_samples_are_clear_errors(sim_loop):
    camera = EurocSequence(sim_loop).camera
    with Tracker(camera, config("orb", lines=False)) as tracker:
        z = np.zeros((3, 3))
        t_ns = np.arange(3, dtype=np.int64) * 5_000_000
        with pytest.raises(InputError, match=r"IMU samples.*shape \(3, 3\)"):
            tracker.add_imu(t_ns, np.zeros((3, 2)), z)
        with pytest.raises(InputError, match=r"IMU samples.*integer nanoseconds.*float64"):
            tracker.add_imu(np.arange(3.0), z, z)  # float seconds: refused, not truncated
        with pytest.raises(InputError, match=r"IMU samples.*not finite"):
            tracker.add_imu(t_ns, np.array([[0.0, 0.0, np.nan], [0, 0, 0], [0, 0, 0]]), z)
        with pytest.raises(InputError, match=r"IMU samples.*increase"):
            tracker.add_imu(np.array([0, 2, 1], dtype=np.int64), z, z)
        tracker.add_imu(t_ns, z, z)
        with pytest.raises(InputError, match=r"IMU samples.*increase"):
            tracker.add_imu(np.array([10_000_000]), np.zeros((1, 3)), np.zeros((1, 3)))


def test_frame_times_in_seconds_and_nanoseconds_agree(sim_loop):
    """track(timestamp=s) and track(t_ns=) land on the same nanosecond (slslam.timestamps, as
    the core's NsFromSeconds); exactly one is needed; a Unix time keeps its nanoseconds."""
    from slslam.timestamps import ns_from_seconds

    assert ns_from_seconds(1403715273.25) == 1_403_715_273_250_000_000
    assert abs(ns_from_seconds(1403715273.262142) - 1_403_715_273_262_142_000) <= 119
    assert ns_from_seconds(-0.0025) == -2_500_000
    sequence = EurocSequence(sim_loop)
    f = sequence[0]
    with Tracker(sequence.camera, config("orb", lines=False)) as tracker:
        with pytest.raises(InputError, match=r"timestamp \[s\] or t_ns \[ns\], once"):
            tracker.track(f.left, f.right)
        with pytest.raises(InputError, match="once"):
            tracker.track(f.left, f.right, 1.0, t_ns=1)
        with pytest.raises(InputError, match="t_ns must be an integer"):
            tracker.track(f.left, f.right, t_ns=1.5)  # type: ignore[arg-type]
        first = tracker.track(f.left, f.right, 1403715273.25)
        assert first.t_ns == 1_403_715_273_250_000_000 and first.timestamp == 1403715273.25
        second = tracker.track(f.left, f.right, t_ns=first.t_ns + 50_000_001)
        assert second.t_ns == 1_403_715_273_300_000_001
        with pytest.raises(InputError, match="does not increase"):
            tracker.track(f.left, f.right, t_ns=second.t_ns)
        final = tracker.final_trajectory()
        assert final.t_ns.dtype == np.int64
        assert final.t_ns.tolist() == [first.t_ns, second.t_ns]


def _row_search_disparities(
    left, right, uv, descriptors, camera, denoise: float = 6.0, window: int | None = None
):
    """(disparity per keypoint or NaN) of the core's stereo matching with the row search
    (its default patch, or a (2 window + 1)^2 one)."""
    rig = _core.StereoRig(
        _core.PinholeCamera(
            camera.fx, camera.fx, camera.cx, camera.cy, camera.width, camera.height
        ),
        camera.baseline_m,
    )
    options = _core.StereoMatchOptions()
    options.row_search = True
    if window is not None:
        options.row_search_window = window
    u_right, _ = _core.match_stereo_points(
        left, right, uv, descriptors, uv[:0], descriptors[:0], rig, options, denoise
    )
    u_right = np.asarray(u_right)
    return np.where(u_right >= 0, uv[:, 0] - u_right, np.nan)


def test_match_stereo_points_returns_arrays_that_outlive_the_call():
    """The binding once returned views of a vector freed on return: the disparities read back were
    whatever the memory held next. A textured pair shifted by 8 px, searched twice with memory
    churned in between: equal results, every depth -1 or positive, the shift found."""
    rng = np.random.default_rng(0)
    texture = rng.uniform(0, 255, (240, 336)).astype(np.float32)
    texture = np.clip(texture, 0, 255).astype(np.uint8)
    left, right = np.ascontiguousarray(texture[:, :320]), np.ascontiguousarray(texture[:, 8:328])
    v, u = np.mgrid[20:220:20, 40:300:20]
    uv = np.stack([u.ravel(), v.ravel()], axis=1).astype(np.float32)
    descriptors = np.zeros((len(uv), 32), np.uint8)
    rig = _core.StereoRig(_core.PinholeCamera(300.0, 300.0, 159.5, 119.5, 320, 240), 0.1)
    options = _core.StereoMatchOptions()
    options.row_search = True
    runs = []
    for _ in range(2):
        u_right, depth = _core.match_stereo_points(
            left, right, uv, descriptors, uv[:0], descriptors[:0], rig, options, 0.0
        )
        runs.append((np.array(u_right).ravel(), np.array(depth).ravel()))
        _churn = [np.full(4096, 7.0) for _ in range(64)]  # reuse of freed memory would show
    (u1, d1), (u2, d2) = runs
    assert np.array_equal(u1, u2) and np.array_equal(d1, d2)
    assert np.all((d1 == -1.0) | (d1 > 0.0))
    found = d1 > 0
    assert found.mean() > 0.8
    np.testing.assert_allclose(uv[found, 0] - u1[found], 8.0, atol=0.1)


@pytest.mark.parametrize("light", [1.0, 0.15])
def test_row_search_disparities_agree_with_the_rendered_depth(light):
    """The row search (no right-image keypoints) against the simulator's depth map. Measured on
    XFeat keypoints of this loop with the 7 x 7 patch: 0.8 % more than 3 px off at full light
    (descriptor matching 5.6 %); in the dark the smoothed search matched about 550 of 2,500
    keypoints, the raw one 16."""
    from slslam.features.orb import Orb, OrbOptions

    sim = Simulator(SimOptions(preset="loop", frames=20, light=light, lidar=False))
    left, right, depth = sim.render_stereo(10)
    camera = sim.camera
    keypoints = Orb(OrbOptions(max_keypoints=1500)).detect(left)
    uv = np.ascontiguousarray(keypoints.uv, dtype=np.float32)
    disparity = _row_search_disparities(left, right, uv, keypoints.descriptors, camera)
    matched = np.isfinite(disparity)
    pixel = np.round(uv[matched]).astype(int)
    truth = camera.fx * camera.baseline_m / depth[pixel[:, 1], pixel[:, 0]]
    error = np.abs(disparity[matched] - truth)
    assert matched.mean() > (0.4 if light == 1.0 else 0.15), matched.mean()
    # (keypoints on depth edges read the depth of the other side: a few percent)
    assert np.median(error) < (0.3 if light == 1.0 else 0.6), np.median(error)
    assert np.mean(error > 3.0) < (0.03 if light == 1.0 else 0.15), np.mean(error > 3.0)
    if light < 1.0:  # the noisy pair is searched smoothed: without it far fewer matches
        raw = _row_search_disparities(left, right, uv, keypoints.descriptors, camera, denoise=0.0)
        assert np.isfinite(raw).sum() < 0.5 * matched.sum()
        # The default 15 x 15 patch against the 7 x 7 one it replaced: in the dark more matches
        # (745 against 565 when measured) and fewer gross errors (0.9 % against 6.5 % over 3 px)
        small = _row_search_disparities(left, right, uv, keypoints.descriptors, camera, window=3)
        small_matched = np.isfinite(small)
        small_pixel = np.round(uv[small_matched]).astype(int)
        small_truth = camera.fx * camera.baseline_m / depth[small_pixel[:, 1], small_pixel[:, 0]]
        small_error = np.abs(small[small_matched] - small_truth)
        assert matched.sum() > 1.15 * small_matched.sum(), (matched.sum(), small_matched.sum())
        assert np.mean(error > 3.0) < 0.5 * np.mean(small_error > 3.0)


def test_row_search_runs_the_front_end_on_the_left_image_only(sim_loop):
    """tracking.stereo_row_search: one detection per frame (the left image), every frame
    tracked, and the trajectory as accurate as with keypoints on both images."""
    from slslam.config import make_point_frontend
    from slslam.eval.report import evaluate
    from slslam.tracking.run import tracked_trajectory

    sequence = EurocSequence(sim_loop)
    base = config("orb", lines=True)
    row = dataclasses.replace(
        base, tracking=dataclasses.replace(base.tracking, stereo_row_search=True)
    )

    class Counting:
        def __init__(self, frontend):
            self.frontend, self.options, self.calls = frontend, frontend.options, 0

        def detect(self, image):
            self.calls += 1
            return self.frontend.detect(image)

    frontend = Counting(make_point_frontend(row.features))
    frames = [(f.left, f.right, f.t_ns * 1e-9) for f in sequence]
    with Tracker(sequence.camera, row, frontend=frontend) as tracker:
        results = list(tracker.track_stream(frames))
    assert frontend.calls == len(frames)
    assert all(r.tracked for r in results[1:])
    gt = sequence.groundtruth(frame="rectified")
    ate = evaluate(tracked_trajectory(results), gt, align="se3", rpe_delta=None, plot=False)
    # ORB + lines with keypoints on both images: 1.3 cm over these 3 m
    assert ate.summary()["ape"]["rmse"] < 0.03


def _positions_and_ate(sequence, configs: dict) -> tuple[dict, dict]:
    """Per named config: the camera positions of a pipelined run over the whole sequence (every
    frame after the first tracked) and its ATE RMSE (SE3) against the rectified ground truth."""
    from slslam.eval.report import evaluate
    from slslam.tracking.run import tracked_trajectory

    frames = [(f.left, f.right, f.t_ns * 1e-9) for f in sequence]
    gt = sequence.groundtruth(frame="rectified")
    positions, ate = {}, {}
    for name, cfg in configs.items():
        with Tracker(sequence.camera, cfg) as tracker:
            results = list(tracker.track_stream(frames))
        assert all(r.tracked for r in results[1:])
        positions[name] = np.array([r.T_world_cam[:3, 3] for r in results])
        summary = evaluate(tracked_trajectory(results), gt, align="se3", rpe_delta=None, plot=False)
        ate[name] = summary.summary()["ape"]["rmse"]
    return positions, ate


def test_matches_are_aligned_to_their_map_points_patches(sim_loop):
    """tracking.track_refine_window_px (on by default): each map point keeps the patch of the
    keyframe that made it and later matches are aligned to it. The image reaches the core's
    tracker through the bindings (the poses change), and the trajectory is at least as accurate
    as with the detected positions (ORB + lines on these 80 frames: 0.0042 against 0.0051 m
    when measured)."""
    sequence = EurocSequence(sim_loop)
    on = config("orb", lines=True)
    assert on.tracking.track_refine_window_px > 0
    off = dataclasses.replace(
        on, tracking=dataclasses.replace(on.tracking, track_refine_window_px=0)
    )
    poses, ate = _positions_and_ate(sequence, {"on": on, "off": off})
    assert np.abs(poses["on"] - poses["off"]).max() > 1e-4, "the refinement changed nothing"
    assert ate["on"] < 0.03
    assert ate["on"] <= 1.1 * ate["off"], ate


def test_pulled_lines_with_the_dogleg_reach_local_ba(sim_loop):
    """tracking.local_ba_line_prior_weight / local_ba_dogleg (off by default): the keys reach the
    core's local BA through the bindings (the poses change) and keep the trajectory accurate
    on these frames."""
    sequence = EurocSequence(sim_loop)
    off = config("orb", lines=True)
    assert off.tracking.local_ba_line_prior_weight == 0.0
    assert not off.tracking.local_ba_dogleg
    on = dataclasses.replace(
        off,
        tracking=dataclasses.replace(
            off.tracking, local_ba_line_prior_weight=10.0, local_ba_dogleg=True
        ),
    )
    poses, ate = _positions_and_ate(sequence, {"off": off, "on": on})
    assert np.abs(poses["on"] - poses["off"]).max() > 1e-5, "the options changed nothing"
    assert ate["on"] < 0.03, ate


def test_lines_held_in_their_weak_directions_reach_local_ba(sim_loop):
    """tracking.local_ba_line_min_information_per_rad2: the key reaches the core's local BA
    (the poses change against 0, which frees every line in all four directions) and the
    trajectory stays accurate on these frames."""
    sequence = EurocSequence(sim_loop)
    base = config("orb", lines=True)
    runs = {
        name: dataclasses.replace(
            base,
            tracking=dataclasses.replace(
                base.tracking, local_ba_line_min_information_per_rad2=value
            ),
        )
        for name, value in (("free", 0.0), ("held", 100.0))
    }
    poses, ate = _positions_and_ate(sequence, runs)
    assert np.abs(poses["held"] - poses["free"]).max() > 1e-5, "the option changed nothing"
    assert ate["held"] < 0.03, ate


def test_right_lines_on_keyframes_only_change_nothing_but_the_work(sim_loop):
    """tracking.right_lines_on_keyframes: the right image's lines are extracted only for frames
    that become keyframes (or start a map), the only ones whose stereo lines are used, so the
    poses and the map are the same as with lines on both images every frame."""
    sequence = EurocSequence(sim_loop)
    lines = config("orb", lines=True)
    assert lines.tracking.right_lines_on_keyframes  # the default
    # (every frame's left lines, so that the frames' lines are those of both images every frame)
    lines = dataclasses.replace(
        lines, tracking=dataclasses.replace(lines.tracking, lines_on_demand=False)
    )
    both = dataclasses.replace(
        lines, tracking=dataclasses.replace(lines.tracking, right_lines_on_keyframes=False)
    )
    runs = []
    for cfg in (both, lines):
        with Tracker(sequence.camera, cfg) as tracker:
            results = [tracker.track(f.left, f.right, f.t_ns * 1e-9) for f in sequence]
            runs.append((tracker.trajectory()[1], tracker.map(), results))
    (poses_a, map_a, results_a), (poses_b, map_b, results_b) = runs
    assert np.array_equal(poses_a, poses_b)
    assert np.array_equal(map_a.lines, map_b.lines) and len(map_a.lines) > 20
    assert [r.counts.keyframe for r in results_a] == [r.counts.keyframe for r in results_b]
    assert sum(r.counts.keyframe for r in results_b) < 0.8 * len(results_b)  # work was skipped


def test_lines_on_demand_skip_the_lines_of_frames_tracked_well_on_their_points(sim_loop):
    """tracking.lines_on_demand: the left image's lines only for the frames that use them.

    With a bound no frame reaches, every frame asks for its lines before it is tracked: the
    poses and the map are those of lines on every frame, whether the lines were extracted ahead
    beside the point front end or by the core when it asked. With the default bound the bright
    loop's frames between keyframes are tracked on their points alone, every keyframe still has
    its lines (matched into the local map from the pose its points gave), the trajectory stays
    accurate, and the pipeline (whose guesses of which frames need lines come from older
    results) gives the poses of the sequential run."""
    sequence = EurocSequence(sim_loop)
    frames = [(f.left, f.right, f.t_ns * 1e-9) for f in sequence]
    demand = config("orb", lines=True)
    assert demand.tracking.lines_on_demand  # the default

    def with_tracking(**changes):
        return dataclasses.replace(demand, tracking=dataclasses.replace(demand.tracking, **changes))

    base = with_tracking(lines_on_demand=False)  # every frame's lines
    always = with_tracking(lines_on_demand_inliers=1_000_000)
    runs = {}
    for name, cfg, ahead in (
        ("every", base, True),
        ("always", always, True),
        ("always, by the core", always, False),
        ("demand", demand, True),
    ):
        with Tracker(sequence.camera, cfg) as tracker:
            if not ahead:
                tracker._lines_side.shutdown()
                tracker._lines_side = None
            results = [tracker.track(*f) for f in frames]
            runs[name] = (tracker.trajectory()[1], tracker.map(), results)
    poses_every, map_every, results_every = runs["every"]
    assert map_every.stats.line_frames == len(frames)
    for name in ("always", "always, by the core"):
        poses, m, results = runs[name]
        assert np.array_equal(poses, poses_every), name
        assert np.array_equal(m.lines, map_every.lines), name
        assert [r.counts.lines for r in results] == [r.counts.lines for r in results_every]

    poses, m, results = runs["demand"]
    assert all(r.tracked for r in results)
    skipped = sum(r.counts.lines == 0 for r in results)
    assert m.stats.line_frames == len(frames) - skipped
    assert skipped > 0.2 * len(frames), skipped  # the work saved
    keyframes = [r for r in results if r.counts.keyframe]
    assert len(keyframes) > 5 and all(r.counts.lines > 20 for r in keyframes)
    assert len(m.lines) > 20
    with Tracker(sequence.camera, demand) as tracker:
        streamed = list(tracker.track_stream(frames))
    assert np.array_equal(np.array([r.T_world_cam for r in streamed]), poses)
    _, ate = _positions_and_ate(sequence, {"every": base, "demand": demand})
    # Measured 0.0042 m (every frame) and 0.0037 m (on demand) on these 80 frames.
    assert ate["demand"] < 0.01, ate


def noisy_frames(sequence: EurocSequence, count: int, seed: int) -> list:
    """The first ``count`` frames as (left, right, t) with white noise of sigma 9 gray levels
    (noisier than tracking.denoise_above_noise's 6: the tracker smooths them)."""
    rng = np.random.default_rng(seed)

    def noisy(image: np.ndarray) -> np.ndarray:
        return np.clip(image + rng.normal(0, 9, image.shape), 0, 255).astype(np.uint8)

    return [
        (noisy(f.left), noisy(f.right), f.t_ns * 1e-9) for f in (sequence[i] for i in range(count))
    ]


def test_left_lines_extracted_beside_the_front_end_are_the_ones_the_core_would_extract(sim_loop):
    """The left image's lines run on a thread of their own beside the point front end
    (``_core.TrackerCore.extract_left_lines``, handed to ``track``): on noisy frames (smoothed
    first) the lines, poses and map are those of the core extracting them itself, and only the
    work moves."""
    sequence = EurocSequence(sim_loop)
    frames = noisy_frames(sequence, 40, seed=5)
    cfg = config("orb", lines=True)
    # every frame's lines (lines_on_demand: see the test above)
    cfg = dataclasses.replace(
        cfg, tracking=dataclasses.replace(cfg.tracking, lines_on_demand=False)
    )
    runs = []
    for ahead in (True, False):
        with Tracker(sequence.camera, cfg) as tracker:
            assert tracker._lines_side is not None  # the default moves them
            if not ahead:
                tracker._lines_side.shutdown()
                tracker._lines_side = None
            results = [tracker.track(*f) for f in frames]
            runs.append((tracker.trajectory()[1], tracker.map(), results))
    (poses_a, map_a, results_a), (poses_b, map_b, results_b) = runs
    assert [r.counts.lines for r in results_a] == [r.counts.lines for r in results_b]
    assert min(r.counts.lines for r in results_a) > 20
    assert np.array_equal(poses_a, poses_b)
    assert np.array_equal(map_a.lines, map_b.lines)
    assert all(r.timings_ms.line_extraction > 0.0 for r in results_a)  # timed on its thread

    # Without lines (or with the right image's lines every frame) the core refuses them.
    no_lines = config("orb", lines=False)
    with Tracker(sequence.camera, no_lines) as tracker:
        assert tracker._lines_side is None
        with pytest.raises(ValueError, match="use_lines"):
            tracker._core.extract_left_lines(frames[0][0])


@pytest.mark.parametrize("smoothed_input", [True, False])
def test_a_front_end_sees_the_smoothed_pair_unless_it_asks_for_the_raw_one(
    sim_loop, smoothed_input
):
    """Noisy frames are smoothed for lines and stereo matching; the point front end gets that
    copy (ORB, XFeat) or, with ``smoothed_input = False`` (SuperPoint, which drifted less on the
    raw dark images), the image as it came."""
    sequence = EurocSequence(sim_loop)
    frames = noisy_frames(sequence, 3, seed=11)

    class Recording:
        def __init__(self):
            self.orb, self.seen = Orb(), []

        def detect(self, image):
            self.seen.append(image)
            return self.orb.detect(image)

    frontend = Recording()
    frontend.smoothed_input = smoothed_input
    with Tracker(sequence.camera, config("orb", lines=False), frontend=frontend) as tracker:
        for left, right, t in frames:
            tracker.track(left, right, t)
    given = [image for f in frames for image in f[:2]]
    assert len(frontend.seen) == len(given)
    for seen in frontend.seen:
        raw = any(np.array_equal(seen, image) for image in given)
        assert raw is (not smoothed_input)
        smoothed = any(np.array_equal(seen, _core.smooth_if_noisy(image, 6.0)) for image in given)
        assert smoothed is smoothed_input


class _Checking:
    """A TrackerCore whose stereo matching and lines check the images' noise again (denoised
    False), recording what the tracker told them."""

    def __init__(self, core, calls: list):
        self._core, self._calls = core, calls

    def __getattr__(self, name):
        return getattr(self._core, name)

    def prepare(self, *args, **kwargs):
        self._calls.append(kwargs.pop("denoised"))
        return self._core.prepare(*args, **kwargs)

    def extract_left_lines(self, image, denoised=False):
        self._calls.append(denoised)
        return self._core.extract_left_lines(image)


def test_a_pair_smoothed_once_is_not_checked_again_and_tracks_the_same(sim_loop):
    """slslam.Tracker smooths each noisy image once and tells ORB, the lines and the core's
    stereo matching so (``denoised_above_noise``, ``denoised``): they skip their own noise check
    (0.1 ms an image each) and the frames track exactly as when every step checks again."""
    sequence = EurocSequence(sim_loop)
    frames = noisy_frames(sequence, 30, seed=7)
    cfg = config("orb", lines=True)
    runs, calls = [], []
    for told in (True, False):
        with Tracker(sequence.camera, cfg) as tracker:
            assert tracker._detect_denoised  # ORB takes the argument
            if not told:
                tracker._detect_denoised = False
                tracker._core = _Checking(tracker._core, calls)
            for f in frames:
                tracker.track(*f)
            runs.append((tracker.trajectory()[1], tracker.map().points))
    assert calls and all(calls)  # the tracker did tell them
    assert len(runs[0][0]) == len(frames) and len(runs[0][1]) > 100
    assert np.array_equal(runs[0][0], runs[1][0])
    assert np.array_equal(runs[0][1], runs[1][1])


def test_orb_skips_its_noise_check_only_for_an_image_smoothed_at_its_threshold_or_below():
    """``Orb.detect(image, denoised_above_noise=t)``: the image came through smooth_if_noisy at
    t. At ORB's own threshold (6) or below, ORB does not smooth again: the same keypoints on the
    smoothed image, and on a raw noisy image (told wrongly) the unsmoothed ones; above it (an
    image ORB would still smooth) ORB checks as without the argument."""
    import cv2

    rng = np.random.default_rng(5)
    base = np.zeros((240, 320), np.uint8)
    base[::16, :] = 180
    base[:, ::24] = 90
    base = cv2.GaussianBlur(base, (0, 0), 2.0)
    raw = np.clip(base + rng.normal(0, 10, base.shape), 0, 255).astype(np.uint8)
    smoothed = _core.smooth_if_noisy(raw, 6.0)
    assert smoothed is not raw
    orb = Orb()

    def same(a, b) -> bool:
        return np.array_equal(a.uv, b.uv) and np.array_equal(a.descriptors, b.descriptors)

    assert len(orb.detect(smoothed)) > 50
    assert same(orb.detect(smoothed, denoised_above_noise=6.0), orb.detect(smoothed))
    assert same(orb.detect(raw), orb.detect(smoothed))  # ORB smooths a noisy image itself
    told = orb.detect(raw, denoised_above_noise=6.0)
    assert same(orb.detect(raw, denoised_above_noise=4.0), told)
    assert not same(told, orb.detect(raw))  # skipped
    assert same(orb.detect(raw, denoised_above_noise=8.0), orb.detect(raw))  # checked


def test_smooth_if_noisy_returns_a_new_array_only_for_a_noisy_image():
    """The front end's smoothing (tracking.denoise_above_noise): a quiet image is handed back as
    it is; a noisy one is smoothed into a new array, the caller's left unchanged."""
    rng = np.random.default_rng(3)
    quiet = np.tile(np.linspace(40, 200, 160, dtype=np.float32), (120, 1)).astype(np.uint8)
    assert _core.smooth_if_noisy(quiet, 6.0) is quiet
    noisy = np.clip(quiet + rng.normal(0, 9, quiet.shape), 0, 255).astype(np.uint8)
    before = noisy.copy()
    smoothed = _core.smooth_if_noisy(noisy, 6.0)
    assert smoothed is not noisy and np.array_equal(noisy, before)
    residual = lambda image: float(np.std(image.astype(np.float32) - quiet))  # noqa: E731
    assert residual(smoothed) < 0.5 * residual(noisy)
    assert _core.smooth_if_noisy(noisy, 0.0) is noisy  # 0: never


def test_projected_keypoints_track_between_detections_the_same_way_in_a_pipeline(sim_loop):
    """``tracking.projected_max_frames``: while tracking is strong the core places the local
    map's points in a frame (projected, aligned to their patches) instead of taking detected
    keypoints, and hands back the frames it cannot (keyframes, after the limit, the frame after
    a keyframe) to be detected. On the bright loop frames between keyframes are projected, never
    more than the limit in a row, every keyframe has detected keypoints, the trajectory stays
    accurate, the pipeline (which chooses ahead which frames to detect) gives the sequential
    run's poses, and no detection is wasted on a frame then projected."""
    sequence = EurocSequence(sim_loop)
    frames = [(f.left, f.right, f.t_ns * 1e-9) for f in sequence]
    base = config("orb", lines=True)
    assert base.tracking.projected_max_frames == 0  # off by default
    # Keyframes at most every 6 frames (as XFeat's preset): with ORB's default of 2 the
    # bright loop makes one every 2-3 frames, and the frame after a keyframe is always detected,
    # which leaves nothing to project.
    base = dataclasses.replace(
        base, tracking=dataclasses.replace(base.tracking, keyframe_min_frames=6)
    )
    projected = dataclasses.replace(
        base, tracking=dataclasses.replace(base.tracking, projected_max_frames=3)
    )
    with Tracker(sequence.camera, projected) as tracker:
        results = [tracker.track(*f) for f in frames]
        poses = tracker.trajectory()[1]
        line_frames = tracker.map().stats.line_frames
    assert all(r.tracked for r in results)
    # frames handed back for detection are counted once, when they come again
    assert line_frames == sum(r.counts.lines > 0 for r in results)
    flags = [r.counts.projected for r in results]
    # (measured 18 of 80: none in the first 15 and the last 26 frames, two or three of every
    # four to six between them)
    assert sum(flags) > 0.15 * len(frames), "".join(map(str, flags))
    assert "1111" not in "".join(map(str, flags))  # at most 3 in a row
    for r in results:
        if r.counts.keyframe:
            assert not r.counts.projected
        if r.counts.projected:
            assert r.counts.keypoints >= projected.tracking.projection_min_inliers
    with Tracker(sequence.camera, projected) as tracker:
        detections = []
        prepare = tracker._prepare_checked

        def counted(index, *args, **kwargs):
            detections.append((index, kwargs["detect"]))
            return prepare(index, *args, **kwargs)

        tracker._prepare_checked = counted
        streamed = list(tracker.track_stream(frames))
    assert np.array_equal(np.array([r.T_world_cam for r in streamed]), poses)
    # Keypoints detected ahead are used: every detection is a frame tracked on its keypoints
    # (ahead, or again after the core handed the frame back), never a projected one.
    detected = [index for index, detect in detections if detect]
    assert all(not streamed[i].counts.projected for i in detected)
    assert sorted(detected) == [r.index for r in streamed if not r.counts.projected]
    _, ate = _positions_and_ate(sequence, {"detected": base, "projected": projected})
    # Measured 0.0030 m (detected) and 0.0034 m (projected) on these 80 frames.
    assert ate["projected"] < 0.01, ate


def test_unaligned_matches_weigh_less_only_in_noisy_frames_with_enough_aligned(tmp_path):
    """tracking.unaligned_sigma_factor: on dark frames (the Python tracker smooths them as noisy
    and tells the core) the matches not aligned to their map points' patches weigh less, which
    moves the poses; gated off by a count of aligned matches no frame reaches, or on bright
    frames (never smoothed), the poses are those of factor 1 to the last bit."""
    frames = 30

    def simulate(light: float) -> EurocSequence:
        out = tmp_path / f"loop_{light}"
        options = SimOptions(preset="loop", light=light, frames=frames, lidar=False)
        Simulator(options).write(out, progress=False)
        return EurocSequence(out)

    def poses(sequence: EurocSequence, factor: float, min_aligned: int) -> np.ndarray:
        base = config("orb", lines=False)
        tracking = dataclasses.replace(
            base.tracking,
            unaligned_sigma_factor=factor,
            unaligned_min_aligned=min_aligned,
        )
        with Tracker(sequence.camera, dataclasses.replace(base, tracking=tracking)) as tracker:
            for i in range(frames):
                f = sequence[i]
                assert tracker.track(f.left, f.right, f.t_ns * 1e-9).tracked
            return np.asarray(tracker.trajectory()[1])

    dark = simulate(0.15)
    plain = poses(dark, 1.0, 0)
    assert not np.array_equal(poses(dark, 3.0, 0), plain)
    assert np.array_equal(poses(dark, 3.0, 10**9), plain)
    bright = simulate(1.0)
    assert np.array_equal(poses(bright, 3.0, 0), poses(bright, 1.0, 0))


def test_the_noisy_keyframe_gap_applies_to_noisy_frames_only(sim_loop, tmp_path):
    """tracking.keyframe_min_frames_noisy: on dark frames (smoothed as noisy) the keyframe gap
    is this instead of keyframe_min_frames, so a shorter one gives more keyframes there, and
    every gap after a keyframe made while tracking is strong is at least it; on bright frames
    (never smoothed) the poses and keyframes are those of -1 (off) to the last bit."""
    frames = 40

    def run(sequence: EurocSequence, noisy_gap: int) -> tuple[np.ndarray, list[int]]:
        base = config("orb", lines=False)
        tracking = dataclasses.replace(
            base.tracking, keyframe_min_frames=8, keyframe_min_frames_noisy=noisy_gap
        )
        with Tracker(sequence.camera, dataclasses.replace(base, tracking=tracking)) as tracker:
            results = []
            for i in range(frames):
                f = sequence[i]
                results.append(tracker.track(f.left, f.right, f.t_ns * 1e-9))
                assert results[-1].tracked
            keyframes = [r.index for r in results if r.counts.keyframe]
            return np.asarray(tracker.trajectory()[1]), keyframes

    out = tmp_path / "dark"
    Simulator(SimOptions(preset="loop", light=0.15, frames=frames, lidar=False)).write(
        out, progress=False
    )
    dark = EurocSequence(out)
    _, off = run(dark, -1)
    _, short = run(dark, 3)
    assert len(short) > len(off), (short, off)
    assert min(np.diff(short)) >= 3, short
    bright = EurocSequence(sim_loop)
    poses_off, keyframes_off = run(bright, -1)
    poses_short, keyframes_short = run(bright, 3)
    assert keyframes_short == keyframes_off
    assert np.array_equal(poses_short, poses_off)


def test_with_the_imu_a_featureless_stretch_longer_than_the_old_bridge_stays_one_map(tmp_path):
    """End to end on the simulated junction (light 0.5) with every light out for 3 s from 4 s on:
    60 frames without a single feature, longer than the 2 s the earlier IMU bridge carried. With
    the simulator's IMU (imu0/) the tracker initialises after about 1 s, carries the dark frames
    (INERTIAL) on its propagated state and comes back into the one map: every frame after
    initialisation posed, one map; metrics.json and frames.csv report the IMU's part."""
    data = tmp_path / "seq"
    Simulator(
        SimOptions(
            preset="junction",
            lidar=False,
            blackout=True,
            blackout_s=3.0,
            blackout_at_s=4.0,
            light=0.5,
            frames=200,
        )
    ).write(data, progress=False)
    summary = run_sequence(data, tmp_path / "run", config("orb", lines=True), progress=False)
    m, results = summary.metrics, summary.results
    assert m["imu"]["has_imu"] and m["imu"]["initialised"], m["imu"]
    assert 0.5 <= m["imu"]["init_after_s"] <= 2.0, m["imu"]
    # The simulated robot drives as a ground vehicle: learned from the tracked frames before the
    # blackout, every dark frame holds its velocity to the axis of travel.
    assert 0.0 <= m["imu"]["travel_side_ratio"] <= 0.1, m["imu"]
    assert m["imu"]["nonholonomic_updates"] >= 55, m["imu"]
    # In the dark the optical flow has nothing to follow: it measures nothing rather than noise.
    assert m["imu"]["flow_updates"] == 0, m["imu"]
    assert m["posed_ratio_after_init"] == 1.0 and m["lost_frames"] == 0
    assert m["maps"] == 1
    t0 = results[0].timestamp  # (the simulator's clock starts at 1000 s)
    dark = [r for r in results if 4.05 <= r.timestamp - t0 < 6.95]
    assert len(dark) >= 55 and all(r.state == "INERTIAL" for r in dark)
    # The frames after the blackout are the camera's again.
    assert all(r.state == "OK" for r in results if r.timestamp - t0 >= 7.5)
    rows = (tmp_path / "run" / "frames.csv").read_text().splitlines()
    header = rows[0].split(",")
    sigma = [float(row.split(",")[header.index("position_sigma_m")]) for row in rows[1:]]
    imu = [int(row.split(",")[header.index("imu")]) for row in rows[1:]]
    assert imu[0] == 0 and imu[-1] == 1
    # Dead reckoning: the position's uncertainty grows through the dark and shrinks after it.
    dark_idx = [i for i, r in enumerate(results) if 4.05 <= r.timestamp - t0 < 6.95]
    assert sigma[dark_idx[-1]] > 5 * sigma[dark_idx[0]] and sigma[-1] < sigma[dark_idx[-1]]

    # The inertial state's columns: the speed the robot drives at (the world is the map's, so
    # the speed, not the vector, compares with the simulator's), biases of an EuRoC-grade IMU.
    def column(name: str) -> np.ndarray:
        return np.array([float(row.split(",")[header.index(name)]) for row in rows[1:]])

    speed = np.linalg.norm(np.stack([column(f"v_world_{a}_mps") for a in "xyz"], 1), axis=1)
    acc_bias = np.stack([column(f"acc_bias_{a}_mps2") for a in "xyz"], 1)
    gyro_bias = np.stack([column(f"gyro_bias_{a}_radps") for a in "xyz"], 1)
    assert speed[0] == 0.0 and not acc_bias[0].any()  # before initialisation: zero
    truth = np.linalg.norm(
        Simulator(SimOptions(preset="junction", frames=200, lidar=False)).trajectory.velocity(
            np.array([r.timestamp - t0 for r in results])
        ),
        axis=1,
    )
    after = [i for i, r in enumerate(results) if imu[i] and r.timestamp - t0 >= 7.5]
    assert np.max(np.abs(speed[after] - truth[after])) < 0.1, np.abs(speed - truth).max()
    assert np.all(np.abs(acc_bias[after]) < 0.1) and np.all(np.abs(gyro_bias[after]) < 5e-3)
    assert m["ape"]["rmse"] < 0.15
