"""Loop closing, map merging, map files and localisation-only mode, end to end on a simulated
loop driven a bit more than once (the robot comes back to where it started)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from slslam.config import config_from_dict
from slslam.errors import InputError
from slslam.sim import SimOptions, Simulator
from slslam.tracking import run_sequence

# A small yard loop (2 m straights, 4 m half circles: 29 m a lap) at 2 m/s and 10 Hz; 175
# frames drive 1.2 laps, so the last 6 m revisit the first.
LOOP = dict(
    preset="loop",
    frames=175,
    rate_hz=10.0,
    speed_mps=2.0,
    laps=2,
    loop_length_m=2.0,
    loop_radius_m=4.0,
    lidar=False,
)


@pytest.fixture(scope="module")
def small_loop(tmp_path_factory):
    out = tmp_path_factory.mktemp("small_loop")
    Simulator(SimOptions(**LOOP)).write(out, progress=False)
    return out


@pytest.fixture(scope="module")
def loop_run(small_loop, tmp_path_factory):
    out = tmp_path_factory.mktemp("loop_run")
    summary = run_sequence(small_loop, out, progress=False, save_map=out / "atlas.slmap")
    return out, summary


def _gt_positions(sequence_dir):
    rows = np.loadtxt(sequence_dir / "groundtruth_cam0.tum")
    return rows[:, 1:4]


def test_the_revisit_closes_a_true_loop_and_the_final_map_is_better(loop_run, small_loop):
    out, summary = loop_run
    m = summary.metrics
    assert m["completed"] and m["tracked_ratio"] == 1.0
    assert m["loops"]["accepted"] >= 1, m["loops"]
    assert m["maps"] == 1
    # Every accepted loop joins two frames that really are at one place (ground truth).
    gt = _gt_positions(small_loop)
    for event in m["loop_events"]:
        gap = np.linalg.norm(gt[event["frame_index"]] - gt[event["candidate_frame_index"]])
        assert gap < 1.5, event
        assert event["frame_index"] - event["candidate_frame_index"] > 100  # a lap apart
    # The final trajectory (frames following their corrected keyframes) beats the online one.
    assert m["ape"]["rmse"] < m["ape_online"]["rmse"]
    assert (out / "trajectory_online.tum").is_file()
    assert len(np.loadtxt(out / "trajectory.tum")) == m["tracked_frames"]
    assert m["global_ba_runs"] >= 1


def test_a_saved_map_localises_a_second_pass_without_changing(loop_run, small_loop, tmp_path):
    out, summary = loop_run
    atlas = out / "atlas.slmap"
    assert atlas.is_file()
    again = run_sequence(
        small_loop,
        tmp_path,
        max_frames=60,
        progress=False,
        load_map=atlas,
        localise_only=True,
    )
    m = again.metrics
    assert m["completed"]
    assert m["tracked_ratio"] == 1.0  # every frame posed in the loaded map
    assert m["keyframes"] == summary.metrics["keyframes"]  # nothing added
    assert m["ape"]["rmse"] < 0.1
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert saved["states"].get("NEW_MAP", 0) == 0


def test_a_map_with_other_line_descriptors_is_refused(loop_run, small_loop, tmp_path):
    out, _ = loop_run
    other = config_from_dict({"tracking": {"line_descriptor": "lbd"}})
    with pytest.raises(InputError, match=r"atlas\.slmap.*lines carry opencv_lbd descriptors"):
        run_sequence(
            small_loop, tmp_path, other, max_frames=2, progress=False, load_map=out / "atlas.slmap"
        )


def test_a_map_loads_only_with_the_vocabulary_it_was_made_with(loop_run, small_loop, tmp_path):
    """The map file stores its vocabulary's identity (file name and checksum): another ORB
    vocabulary is refused with the reason, the map's own loads."""
    from slslam import _core
    from slslam.place import Vocabulary, VocabularyOptions

    out, _ = loop_run
    header = _core.read_map_file_header(str(out / "atlas.slmap"))
    assert header["vocabulary"].startswith("orb_vocabulary.slvoc@")
    assert len(header["vocabulary"].split("@")[1]) == 16
    rng = np.random.default_rng(0)
    images = [rng.integers(0, 256, size=(200, 32), dtype=np.uint8) for _ in range(8)]
    other = tmp_path / "other.slvoc"
    Vocabulary.train(images, VocabularyOptions(branching=4, levels=2)).save(other)
    config = config_from_dict({"tracking": {"vocabulary_path": str(other)}})
    with pytest.raises(InputError, match=r"atlas\.slmap: the map was made with the vocabulary "):
        run_sequence(
            small_loop,
            tmp_path / "a",
            config,
            max_frames=2,
            progress=False,
            load_map=out / "atlas.slmap",
        )


def test_bad_map_files_are_clear_errors(small_loop, tmp_path):
    broken = tmp_path / "broken.slmap"
    broken.write_bytes(b"not a map at all")
    with pytest.raises(InputError, match=r"broken\.slmap"):
        run_sequence(small_loop, tmp_path / "a", max_frames=2, progress=False, load_map=broken)
    with pytest.raises(InputError, match="map file not found"):
        run_sequence(
            small_loop, tmp_path / "b", max_frames=2, progress=False, load_map=tmp_path / "x"
        )
    with pytest.raises(InputError, match="needs a map"):
        run_sequence(small_loop, tmp_path / "c", max_frames=2, progress=False, localise_only=True)
