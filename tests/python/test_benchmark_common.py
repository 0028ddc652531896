"""benchmarks/common.py: the speed reference that puts runs of different machines side by side."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import load_benchmark


@pytest.fixture(scope="module")
def common():
    yield from load_benchmark("common.py")


def test_speed_reference_times_the_core_orb_on_the_given_image(common):
    rng = np.random.default_rng(0)
    image = np.kron(rng.integers(0, 256, (60, 94), dtype=np.uint8), np.ones((8, 8), np.uint8))
    ms = common.speed_reference_ms(image, repeats=3)
    assert math.isfinite(ms) and ms > 0.0
    with pytest.raises(ValueError):  # a colour image is refused by the core, not timed
        common.speed_reference_ms(np.zeros((48, 64, 3), np.uint8), repeats=1)
