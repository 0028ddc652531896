"""pip's OpenCV (``cv2``, opencv-python-headless) and the Debian OpenCV linked into slslam._core
live in one process, imported in either order, and agree on what they both do."""

from __future__ import annotations

import subprocess
import sys

import pytest

SCRIPT = """
import sys
import numpy as np
first = sys.argv[1]
if first == "cv2":
    import cv2
    from slslam import _core
else:
    from slslam import _core
    import cv2
path = sys.argv[2]
rng = np.random.default_rng(0)
image = rng.integers(0, 256, (64, 80), dtype=np.uint8)
assert cv2.imwrite(path, image)
ours = _core.read_gray_image(path)           # Debian libopencv_imgcodecs 4.x
theirs = cv2.imread(path, cv2.IMREAD_GRAYSCALE)  # pip's bundled OpenCV
assert np.array_equal(ours, image) and np.array_equal(theirs, image)
# Both ORB implementations run in the same process (the extension's through C++, pip's in cv2).
orb = _core.extract_orb(np.ascontiguousarray(np.tile(image, (4, 4))))
kp = cv2.ORB_create(200).detect(np.tile(image, (4, 4)), None)
assert len(kp) > 0 and len(orb[0]) > 0
print("ok", cv2.__version__)
"""


@pytest.mark.parametrize("first", ["cv2", "core"])
def test_pip_and_debian_opencv_in_one_process(first, tmp_path):
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT, first, str(tmp_path / "image.png")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.startswith("ok ")
