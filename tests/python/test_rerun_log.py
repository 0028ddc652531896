"""A short run recorded to an .rrd with rerun, headless, and read back with rerun's own reader:
the logged entities are there with one row per frame where they should be."""

from __future__ import annotations

import dataclasses
import os
from collections import Counter
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from slslam.config import Config
from slslam.datasets import EurocSequence
from slslam.sim import SimOptions, Simulator
from slslam.tracking import Tracker
from slslam.tracking.run import tracked_trajectory
from slslam.viz.rerun_log import RerunLogger

FRAMES = 20


@pytest.fixture(scope="module")
def sim_sequence(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("rerun") / "seq"
    Simulator(SimOptions(preset="loop", frames=FRAMES, lidar=False)).write(out, progress=False)
    return out


def read_rrd(path: Path) -> tuple[Counter, dict]:
    """Rows per entity path on the timelines (static rows apart, under "static:<path>"), and the
    last record batch per entity."""
    from rerun.chunk import RrdReader

    rows: Counter = Counter()
    batches: dict = {}
    for chunk in RrdReader(str(path)).stream():
        key = f"static:{chunk.entity_path}" if chunk.is_static else chunk.entity_path
        rows[key] += chunk.num_rows
        batches[chunk.entity_path] = chunk.to_record_batch()
    return rows, batches


def test_recording_holds_the_run(sim_sequence, tmp_path):
    seq = EurocSequence(sim_sequence)
    base = Config()
    config = dataclasses.replace(
        base, features=dataclasses.replace(base.features, point_frontend="orb")
    )
    rrd = tmp_path / "run.rrd"
    with Tracker(seq.camera, config) as tracker, RerunLogger(seq.camera, rrd) as viewer:
        results = []
        for frame in seq:
            result = tracker.track(frame.left, frame.right, frame.t_ns * 1e-9)
            results.append(result)
            assert np.array_equal(tracker.last_image, frame.left)
            viewer.log_frame(result, tracker.last_image, tracker.last_keypoints_uv)
            if viewer.wants_map(result.index):
                viewer.log_map(tracker.map())
        map_data = tracker.map()
        viewer.log_map(map_data)
        viewer.log_groundtruth(tracked_trajectory(results), seq.groundtruth("rectified"))
        viewer.log_metrics({"tracked_ratio": 1.0})
    rows, batches = read_rrd(rrd)
    for entity in ("/world/camera", "/world/camera/image", "/world/camera/image/keypoints",
                   "/world/camera/image/lines", "/state", "/timings/total",
                   "/timings/line_extraction", "/counts/inlier_points"):  # fmt: skip
        assert rows[entity] == FRAMES, (entity, rows)
    tracked = sum(r.state in ("OK", "NEW_MAP", "RELOCALISED") for r in results)
    assert tracked >= FRAMES - 2
    assert rows["/world/trajectory"] == tracked
    assert rows["/world/keyframes"] == sum(r.counts.keyframe for r in results) >= 1
    assert rows["/world/map/points"] >= 1 and rows["/world/map/lines"] >= 1
    assert rows["static:/world/groundtruth"] == 1 and rows["static:/summary"] == 1
    assert rows["static:/world/camera/image"] == 1  # the pinhole model

    # The last map logged is the final map, point for point.
    positions = batches["/world/map/points"].column("Points3D:positions")[-1].as_py()
    assert np.allclose(np.array(positions), map_data.points, atol=1e-5)
    # The ground truth, moved into the map frame, lies on the estimated path (simulated: exact
    # images, so within a few centimetres).
    gt = np.array(batches["/world/groundtruth"].column("LineStrips3D:strips")[0].as_py()[0])
    est = np.array([r.T_world_cam[:3, 3] for r in results if r.state == "OK"])
    assert len(gt) >= tracked - 1
    assert np.median(np.linalg.norm(gt[:, None, :] - est[None, :, :], axis=2).min(axis=1)) < 0.05
    # Per-stage timings are the tracker's numbers.
    totals = batches["/timings/total"].column("Scalars:scalars")
    assert totals[len(totals) - 1].as_py() == [pytest.approx(results[-1].timings_ms.total)]


def test_bad_arguments(tmp_path):
    camera = EurocSequence  # any object: the checks come first
    with pytest.raises(ValueError, match="needs a recording file"):
        RerunLogger(camera)
    with pytest.raises(ValueError, match=r"ends in \.rrd"):
        RerunLogger(camera, tmp_path / "run.txt")
    with pytest.raises(ValueError, match="jpeg_quality"):
        RerunLogger(camera, tmp_path / "run.rrd", jpeg_quality=101)


def test_cli_records_a_run(sim_sequence, tmp_path):
    """`slslam run SEQ --rerun FILE.rrd`: the recording holds every frame, the map and the ground
    truth, next to the usual outputs."""
    from typer.testing import CliRunner

    from slslam.cli import app

    config = tmp_path / "orb.yaml"
    config.write_text("features:\n  point_frontend: orb\n")
    rrd = tmp_path / "view" / "run.rrd"
    done = CliRunner().invoke(app, ["run", str(sim_sequence), "--out", str(tmp_path / "out"),
                                    "--config", str(config), "--max-frames", "12",
                                    "--rerun", str(rrd), "--no-progress"])  # fmt: skip
    assert done.exit_code == 0, done.output
    assert "rerun recording in" in done.output
    rows, _ = read_rrd(rrd)
    assert rows["/world/camera"] == 12 and rows["/world/camera/image/keypoints"] == 12
    assert rows["/world/map/points"] >= 1 and rows["static:/world/groundtruth"] == 1
    assert (tmp_path / "out" / "trajectory.tum").is_file()
    bad = CliRunner().invoke(app, ["run", str(sim_sequence), "--out", str(tmp_path / "o2"),
                                   "--rerun", str(tmp_path / "run.txt")])  # fmt: skip
    assert bad.exit_code != 0 and "ends in .rrd" in str(bad.exception)


@pytest.mark.skipif(
    bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")),
    reason="a display is present: the spawned viewer would open a window",
)
def test_viewer_without_a_display_falls_back_to_the_file(tmp_path):
    """--viewer on a machine without a display: the recording still goes to the file (one
    warning); without a file it is a clear error, not a crash at the end of the run."""
    camera = SimpleNamespace(fx=100.0, fy=100.0, cx=50.0, cy=40.0, width=100, height=80)
    rrd = tmp_path / "run.rrd"
    with RerunLogger(camera, rrd, spawn=True) as viewer:
        viewer.log_map(SimpleNamespace(points=np.zeros((4, 3)), lines=np.zeros((1, 6))))
    rows, _ = read_rrd(rrd)
    assert rows["/world/map/points"] == 1
    with pytest.raises(ValueError, match="viewer is not reachable"):
        RerunLogger(camera, spawn=True)
