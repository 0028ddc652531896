"""slslam.viz draws with OpenCV: the PNG has the canvas size, and the marks land where asked."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from slslam.viz import draw_features, draw_matches
from slslam.viz.features import TITLE_PX


def test_draw_features_marks_keypoints_and_segments(tmp_path):
    image = np.full((60, 80), 50, np.uint8)
    path = draw_features(tmp_path / "f.png", image, np.array([[10.0, 20.0]]),
                         np.array([[40.0, 5.0, 40.0, 50.0]]), "title")  # fmt: skip
    drawn = cv2.imread(str(path))
    assert drawn.shape == (60 + TITLE_PX, 80, 3)
    b, g, r = drawn[20 + TITLE_PX, 10]
    assert g > 200 and b < 80 and r < 80  # green keypoint
    b, g, r = drawn[30 + TITLE_PX, 40]
    assert r > 200 and 100 < g < 180 and b < 80  # orange segment
    assert tuple(drawn[45 + TITLE_PX, 70]) == (50, 50, 50)  # untouched


def test_draw_matches_side_by_side(tmp_path):
    a = np.zeros((40, 50), np.uint8)
    b = np.zeros((30, 60), np.uint8)
    path = draw_matches(tmp_path / "m.png", a, b, np.array([[5.0, 10.0]]), np.array([[5.0, 10.0]]),
                        np.array([[0, 0]]))  # fmt: skip
    drawn = cv2.imread(str(path))
    assert drawn.shape == (40 + TITLE_PX, 110, 3)
    assert drawn[10 + TITLE_PX, 30, 1] > 100  # the match line crosses to the second image
    with pytest.raises(OSError, match="cannot write"):
        draw_features(tmp_path / "f.unknown", a)
