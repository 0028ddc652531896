"""Point front ends declare what their ``detect`` takes (slslam.features.PointFrontEnd): every
built-in one declares all of it, a front end of one's own may leave it out (the documented
defaults) and the tracker refuses one that does not fit with a TypeError naming what is wrong."""

from __future__ import annotations

import inspect

import cv2
import numpy as np
import pytest

from slslam.config import Config
from slslam.datasets.euroc import RectifiedStereoCamera
from slslam.features import (
    FrontEndCapabilities,
    Keypoints,
    PointFrontEnd,
    SuperPoint,
    XFeat,
    frontend_capabilities,
)
from slslam.features.frontend import CAPABILITIES
from slslam.features.orb import Orb
from slslam.tracking import Tracker

#: capability -> the keyword of detect it declares (smoothed_input: none, it is about the image)
KEYWORDS = {
    "detect_takes_threshold": "threshold",
    "detect_takes_select": "select",
    "detect_takes_denoised": "denoised_above_noise",
}


@pytest.mark.parametrize("cls", [Orb, XFeat, SuperPoint])
def test_every_builtin_front_end_declares_its_capabilities(cls):
    for attribute in CAPABILITIES:
        assert attribute in vars(cls), f"{cls.__name__} does not declare {attribute}"
        assert isinstance(vars(cls)[attribute], bool)
    # The declarations say what detect takes.
    parameters = inspect.signature(cls.detect).parameters
    for attribute, keyword in KEYWORDS.items():
        assert getattr(cls, attribute) is (keyword in parameters), (cls.__name__, attribute)
    assert cls.smoothed_input is (cls is not SuperPoint)


def test_a_front_end_without_the_attributes_gets_the_documented_defaults():
    class Plain:
        def detect(self, image):
            raise AssertionError("not called")

    assert frontend_capabilities(Plain()) == FrontEndCapabilities()
    assert FrontEndCapabilities() == FrontEndCapabilities(**CAPABILITIES)
    assert {k: getattr(PointFrontEnd, k) for k in CAPABILITIES} == CAPABILITIES

    class Declared(PointFrontEnd):  # subclassing the protocol inherits the defaults
        detect_takes_threshold = True

        def __init__(self):
            self.options = type("Options", (), {"detection_threshold": 0.01})()

        def detect(self, image):
            raise AssertionError("not called")

    declared = frontend_capabilities(Declared())
    assert declared.detect_takes_threshold and declared.smoothed_input
    assert declared.detection_threshold == 0.01


def _camera(width: int = 320, height: int = 240) -> RectifiedStereoCamera:
    return RectifiedStereoCamera(
        fx=300.0, fy=300.0, cx=width / 2, cy=height / 2, width=width, height=height,
        baseline_m=0.1, T_body_cam=np.eye(4),
    )  # fmt: skip


def _pair(seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    left = cv2.GaussianBlur(rng.integers(0, 256, (240, 320), dtype=np.uint8), (5, 5), 1.5)
    return left, np.roll(left, -8, axis=1)


class Recording:
    """ORB behind a detect that records its keywords; capabilities set per test."""

    def __init__(self):
        self.orb, self.calls = Orb(), []
        self.options = type("Options", (), {"detection_threshold": 0.05})()

    def detect(self, image: np.ndarray, **keywords) -> Keypoints:
        self.calls.append(sorted(keywords))
        select = keywords.pop("select", None)
        keypoints = self.orb.detect(image)
        if select is not None:
            keypoints = keypoints.select(np.asarray(select(keypoints.uv, keypoints.scores)))
        return keypoints


def _track_two(frontend) -> list[list[str]]:
    config = Config()
    with Tracker(_camera(), config, frontend=frontend) as tracker:
        for k in range(2):
            tracker.track(*_pair(k), float(k))
    return frontend.calls


def test_the_tracker_passes_only_the_keywords_a_front_end_declares():
    plain = Recording()
    assert _track_two(plain) == [[], [], [], []]  # no attributes: a plain detect(image)
    declared = Recording()
    declared.detect_takes_threshold = True
    declared.detect_takes_select = True
    assert _track_two(declared) == [["select", "threshold"]] * 4


def test_a_front_end_that_does_not_fit_is_refused_by_name():
    class NoDetect:
        def extract(self, image):
            return None

    with pytest.raises(TypeError, match=r"NoDetect has no detect\(image\)"):
        Tracker(_camera(), Config(), frontend=NoDetect())

    class Worded(Recording):
        smoothed_input = "yes"

    with pytest.raises(TypeError, match=r"Worded: smoothed_input must be True or False, got 'yes'"):
        Tracker(_camera(), Config(), frontend=Worded())
