"""The typed API: frame names in results (``T_world_cam``, with ``T_wc`` as a deprecated alias),
typed per-frame results (``StageTimings``, ``FrameCounts``, the core's ``FrameOutput``) and
``Tracker.track`` taking what ``cv2.imread`` gives (gray, BGR, 16-bit)."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from slslam import _core
from slslam.config import Config
from slslam.datasets import EurocSequence
from slslam.errors import InputError
from slslam.sim import SimOptions, Simulator
from slslam.tracking import FrameCounts, StageTimings, Tracker

FRAMES = 8


@pytest.fixture(scope="module")
def sequence(tmp_path_factory) -> EurocSequence:
    out = tmp_path_factory.mktemp("typed") / "seq"
    Simulator(SimOptions(preset="loop", frames=FRAMES, lidar=False)).write(out, progress=False)
    return EurocSequence(out)


def orb_config() -> Config:
    base = Config()
    return dataclasses.replace(
        base, features=dataclasses.replace(base.features, point_frontend="orb")
    )


def run(sequence: EurocSequence, convert) -> list[np.ndarray]:
    with Tracker(sequence.camera, orb_config()) as tracker:
        return [
            tracker.track(convert(f.left), convert(f.right), f.t_ns * 1e-9).T_world_cam
            for f in sequence
        ]


def test_track_takes_what_cv2_loads(sequence, tmp_path):
    gray = run(sequence, lambda im: im)
    # BGR as cv2.imread(path) gives for a gray PNG, through a real file round trip.
    path = tmp_path / "frame.png"

    def via_cv2(image: np.ndarray) -> np.ndarray:
        cv2.imwrite(str(path), image)
        bgr = cv2.imread(str(path))
        assert bgr.shape == (*image.shape, 3)
        return bgr

    assert np.array_equal(np.array(run(sequence, via_cv2)), np.array(gray))
    # 16-bit (12-bit data in 16-bit words, as machine-vision cameras store it): scaled by 1/16.
    twelve_bit = run(sequence, lambda im: im.astype(np.uint16) << 4)
    assert np.array_equal(np.array(twelve_bit), np.array(gray))
    # BGRA, and the pose name's deprecated alias.
    with Tracker(sequence.camera, orb_config()) as tracker:
        frame = sequence[0]
        result = tracker.track(cv2.cvtColor(frame.left, cv2.COLOR_GRAY2BGRA),
                               cv2.cvtColor(frame.right, cv2.COLOR_GRAY2BGRA), 1.0)  # fmt: skip
        with pytest.warns(DeprecationWarning, match="T_world_cam"):
            assert result.T_wc is result.T_world_cam
        with pytest.raises(InputError, match=r"frame 1.*float32"):
            tracker.track(frame.left.astype(np.float32), frame.right, 2.0)
        with pytest.raises(InputError, match=r"frame 1.*gray, BGR or BGRA"):
            tracker.track(np.dstack([frame.left, frame.left]), frame.right, 2.0)


def test_results_are_typed_not_dicts(sequence):
    with Tracker(sequence.camera, orb_config()) as tracker:
        results = [tracker.track(f.left, f.right, f.t_ns * 1e-9) for f in sequence]
    last = results[-1]
    assert last.tracked
    assert isinstance(last.timings_ms, StageTimings) and isinstance(last.counts, FrameCounts)
    # Every field typed and filled from the core: the frame's own work includes its stages (the
    # left image's lines run beside the point front end, so the longer of the two counts).
    t = last.timings_ms
    assert all(isinstance(v, float) for v in t.as_dict().values())
    assert t.line_extraction > 0 and t.inference > 0
    assert t.total >= max(t.inference, t.line_extraction) + t.stereo_matching + t.matching
    c = last.counts
    assert c.keypoints > 100 and c.inlier_points > 50 and c.map == 0 and c.lines >= 0
    # (tracking.lines_on_demand: keyframes and thinly tracked frames take lines, others none)
    assert any(r.counts.lines > 0 for r in results) and results[0].counts.lines > 0
    assert c.inlier_points <= c.matched_points
    assert results[0].counts.keyframe == 1  # the first frame starts the map
    assert list(c.as_dict()) == [f.name for f in dataclasses.fields(FrameCounts)]
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.keypoints = 0  # type: ignore[misc]
    # The dict interface of the previous release still reads, with a deprecation warning.
    with pytest.warns(DeprecationWarning, match=r"FrameCounts\[key\] is deprecated"):
        assert c["inlier_points"] == c.inlier_points
    with pytest.warns(DeprecationWarning, match="StageTimings"):
        assert dict(t.items()) == t.as_dict()
    with pytest.warns(DeprecationWarning), pytest.raises(KeyError):
        c["no_such_count"]


def test_core_returns_a_bound_frame_output(sequence):
    """The private core hands back a bound struct with the pose as cam_from_world (4x4)."""

    class Spy:  # records what the core returns
        def __init__(self, core):
            self.core, self.outputs = core, []

        def track_prepared(self, *args):  # the core's part of Tracker.track
            self.outputs.append(self.core.track_prepared(*args))
            return self.outputs[-1]

        def __getattr__(self, name):
            return getattr(self.core, name)

    with Tracker(sequence.camera, orb_config()) as tracker:
        spy = Spy(tracker._core)
        tracker._core = spy
        results = [tracker.track(f.left, f.right, f.t_ns * 1e-9) for f in sequence]
        tracker._core = spy.core
    assert all(isinstance(o, _core.FrameOutput) for o in spy.outputs)
    for out, result in zip(spy.outputs, results, strict=True):
        T = out.cam_from_world
        assert T.shape == (4, 4) and np.array_equal(T[3], [0, 0, 0, 1])
        assert np.array_equal(np.linalg.inv(T), result.T_world_cam)
        assert out.state == result.state and out.inlier_points == result.counts.inlier_points
        assert out.line_extraction_ms == result.timings_ms.line_extraction
