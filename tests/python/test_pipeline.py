"""The tracker's frame pipeline (``Tracker.track_stream``): the front end of the next frames on a
worker thread while the core tracks frame k gives the same poses as ``track`` in a loop,
prepares at most ``frames_ahead`` frames ahead, and reports a bad frame after the results of the
frames before it."""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import pytest

from slslam.config import Config, ConfigError, load_config
from slslam.datasets import EurocSequence
from slslam.errors import InputError
from slslam.sim import SimOptions, Simulator
from slslam.tracking import Tracker

FRAMES = 24


@pytest.fixture(scope="module")
def sequence(tmp_path_factory) -> EurocSequence:
    out = tmp_path_factory.mktemp("sim") / "loop"
    Simulator(SimOptions(preset="loop", frames=FRAMES, lidar=False)).write(out, progress=False)
    return EurocSequence(out)


def orb_lines() -> Config:
    base = Config()
    features = dataclasses.replace(base.features, point_frontend="orb")
    return dataclasses.replace(base, features=features)


def frames_of(sequence: EurocSequence, pulled: list[int] | None = None):
    for i in range(len(sequence)):
        if pulled is not None:
            pulled.append(i)
        f = sequence[i]
        yield f.left, f.right, f.t_ns * 1e-9


@pytest.mark.parametrize("frames_ahead", [1, 3])
def test_pipelined_stream_gives_the_poses_of_a_plain_loop(sequence, frames_ahead):
    with Tracker(sequence.camera, orb_lines()) as tracker:
        for left, right, t in frames_of(sequence):
            tracker.track(left, right, t)
        _, loop_poses, loop_states = tracker.trajectory()
    pulled: list[int] = []
    ahead = []
    config = orb_lines()
    config = dataclasses.replace(
        config,
        tracking=dataclasses.replace(config.tracking, pipeline_frames_ahead=frames_ahead),
    )
    with Tracker(sequence.camera, config) as tracker:
        for result in tracker.track_stream(frames_of(sequence, pulled), pipeline=True):
            ahead.append(len(pulled) - 1 - result.index)  # frames read beyond this result
            if result.index == 2:
                # The core stalls (as on a keyframe): the worker fills the queue and stops there.
                time.sleep(2.0)
                ahead.append(len(pulled) - 1 - result.index)
        _, poses, states = tracker.trajectory()
        indices = [r.index for r in tracker.results]
    assert indices == list(range(FRAMES))
    assert states == loop_states and "OK" in states
    assert np.array_equal(poses, loop_poses)
    # frames_ahead at most (more would mean the worker ran past its slots), and the worker did
    # fill them while the core stalled.
    assert max(ahead) == frames_ahead


def test_stereo_matching_runs_ahead_of_the_core_and_a_frame_is_tracked_once(sequence):
    """The worker's part ends with the frame's stereo matching (TrackerCore.prepare, no lock):
    frame 1 is prepared before frame 0 is tracked, and the poses are those of track()."""
    with Tracker(sequence.camera, orb_lines()) as tracker:
        for left, right, t in frames_of(sequence):
            tracker.track(left, right, t)
            if len(tracker.results) == 2:
                break
        _, expected, _ = tracker.trajectory()
    with Tracker(sequence.camera, orb_lines()) as tracker:
        f0, f1 = sequence[0], sequence[1]
        first = tracker._prepare(0, f0.left, f0.right, f0.t_ns, None)
        second = tracker._prepare(1, f1.left, f1.right, f1.t_ns, f0.t_ns)
        assert first.stereo.stereo_matching_ms > 0.0
        tracker._track_prepared(first)
        tracker._track_prepared(second)
        with pytest.raises(ValueError, match="tracked once"):
            tracker._core.track_prepared(first.stereo)
        _, poses, _ = tracker.trajectory()
        f2 = sequence[2]
        third = tracker._prepare(2, f2.left, f2.right, f2.t_ns, f1.t_ns)
    assert np.array_equal(poses, expected)
    with Tracker(sequence.camera, orb_lines()) as other:  # a frame is its own core's
        with pytest.raises(ValueError, match="TrackerCore that prepared it"):
            other._core.track_prepared(third.stereo)


def test_overlapped_local_mapping_through_the_pipeline_is_reproducible(sequence):
    """tracking.mapping_overlap reaches the core (the poses differ from inline mapping's) and
    keeps the run exactly reproducible: the pipeline with a queue gives the poses of a plain
    loop."""

    def run(overlap: bool, stream: bool) -> np.ndarray:
        config = orb_lines()
        config = dataclasses.replace(
            config, tracking=dataclasses.replace(config.tracking, mapping_overlap=overlap)
        )
        with Tracker(sequence.camera, config) as tracker:
            if stream:
                for _ in tracker.track_stream(frames_of(sequence), frames_ahead=3):
                    pass
            else:
                for left, right, t in frames_of(sequence):
                    tracker.track(left, right, t)
            _, poses, states = tracker.trajectory()
        assert "OK" in states
        return poses

    overlapped = run(True, stream=False)
    assert np.array_equal(run(True, stream=True), overlapped)
    assert not np.array_equal(run(False, stream=False), overlapped)


def test_frames_ahead_is_checked(sequence, tmp_path):
    with Tracker(sequence.camera, orb_lines()) as tracker:
        with pytest.raises(ValueError, match="frames_ahead must be an integer >= 1, got 0"):
            next(tracker.track_stream(frames_of(sequence), frames_ahead=0))
        with pytest.raises(ValueError, match=r"frames_ahead must be an integer >= 1, got 2\.5"):
            next(tracker.track_stream(frames_of(sequence), frames_ahead=2.5))
        assert next(tracker.track_stream(frames_of(sequence), frames_ahead=np.int64(2))).index == 0
    path = tmp_path / "bad.yaml"
    path.write_text("tracking:\n  pipeline_frames_ahead: 0\n")
    with pytest.raises(ConfigError, match=r"bad.yaml.*tracking.pipeline_frames_ahead.*\[1, 64\]"):
        load_config(path)


def test_a_bad_frame_is_raised_after_the_frames_before_it(sequence):
    def frames():
        for k, (left, right, t) in enumerate(frames_of(sequence)):
            yield left, right, (t if k != 5 else 0.0)  # frame 5 goes back in time

    seen = []
    with Tracker(sequence.camera, orb_lines()) as tracker:
        with pytest.raises(InputError, match=r"frame 5.*does not increase"):
            for result in tracker.track_stream(frames()):
                seen.append(result.index)
    assert seen == [0, 1, 2, 3, 4]


def test_a_failing_reader_is_raised_and_stopping_early_stops_the_worker(sequence):
    def frames():
        yield from list(frames_of(sequence))[:3]
        raise OSError("camera unplugged")

    with Tracker(sequence.camera, orb_lines()) as tracker:
        with pytest.raises(OSError, match="camera unplugged"):
            list(tracker.track_stream(frames()))
        assert len(tracker.results) == 3
    pulled: list[int] = []
    with Tracker(sequence.camera, orb_lines()) as tracker:
        stream = tracker.track_stream(frames_of(sequence, pulled), frames_ahead=3)
        next(stream)
        stream.close()
        # the frame tracked and at most the three prepared ahead, of 24
        assert len(tracker.results) == 1 and len(pulled) <= 1 + 3


def test_bad_images_name_the_frame(sequence):
    f = sequence[0]
    with Tracker(sequence.camera, orb_lines()) as tracker:
        with pytest.raises(InputError, match="frame 0"):
            list(tracker.track_stream([(f.left[:-2], f.right, 0.0)]))
