"""The typed API: frame names in results (``T_world_cam``, with ``T_wc`` as a deprecated alias),
and ``Tracker.track`` taking what ``cv2.imread`` gives (gray, BGR, 16-bit)."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from slslam.config import Config
from slslam.datasets import EurocSequence
from slslam.errors import InputError
from slslam.sim import SimOptions, Simulator
from slslam.tracking import Tracker

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
