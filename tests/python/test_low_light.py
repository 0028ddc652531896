"""The low-light stage (features.low_light): which frames it enhances, with what, and a tracker
run on a dark simulated loop with it on."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slslam.config import ConfigError, config_from_dict
from slslam.features.low_light import LowLightEnhancer, LowLightOptions


def _dark_pair(mean: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    left = np.clip(rng.normal(mean, 8.0, size=(48, 64)), 0, 255).astype(np.uint8)
    return left, np.roll(left, 3, axis=1)


def test_gamma_maps_the_left_mean_to_the_target_and_uses_one_curve_for_the_pair():
    enhancer = LowLightEnhancer(LowLightOptions(mode="gamma", target_mean_gray=100.0))
    left, right = _dark_pair(30.0)
    out_left, out_right = enhancer.pair(left, right)
    assert enhancer.applied == 1
    assert out_left.mean() == pytest.approx(100.0, abs=12.0)  # the curve is not linear
    # one tone curve: equal input gray levels give equal outputs in both images
    np.testing.assert_array_equal(np.roll(out_left, 3, axis=1), out_right)
    gamma = enhancer.gamma_for(30.0)
    assert gamma == pytest.approx(math.log(100 / 255) / math.log(30 / 255))
    # monotonic: the order of gray levels is kept
    order = np.argsort(left.ravel(), kind="stable")
    assert np.all(np.diff(out_left.ravel()[order].astype(int)) >= 0)


def test_bright_frames_and_mode_none_pass_unchanged():
    left, right = _dark_pair(120.0)
    for mode in ("gamma", "clahe"):
        enhancer = LowLightEnhancer(LowLightOptions(mode=mode))
        out = enhancer.pair(left, right)
        assert out[0] is left and out[1] is right and enhancer.applied == 0
    dark = _dark_pair(20.0)
    out = LowLightEnhancer(LowLightOptions()).pair(*dark)
    assert out[0] is dark[0] and out[1] is dark[1]


def test_gamma_is_bounded_by_min_gamma():
    enhancer = LowLightEnhancer(LowLightOptions(mode="gamma", min_gamma=0.5))
    assert enhancer.gamma_for(1.0) == 0.5
    assert enhancer.gamma_for(59.0) > 0.5


def test_clahe_raises_local_contrast_of_a_dark_pair():
    enhancer = LowLightEnhancer(LowLightOptions(mode="clahe", clahe_tile_px=16))
    left, right = _dark_pair(25.0)
    out_left, out_right = enhancer.pair(left, right)
    assert enhancer.applied == 1
    assert out_left.std() > 1.5 * left.std() and out_right.std() > 1.5 * right.std()


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("mode", "bright", "must be one of"),
        ("min_gamma", 0.0, r"min_gamma' must be a finite number in \[0.05, 1\]"),
        ("target_mean_gray", 300.0, r"target_mean_gray' must be a finite number in \[1, 254\]"),
        ("clahe_tile_px", 4, r"clahe_tile_px' must be an integer in \[8, 4096\]"),
        ("below_mean_gray", True, "below_mean_gray"),
    ],
)
def test_bad_options_name_the_key(key, value, message):
    with pytest.raises(ConfigError, match=message) as info:
        config_from_dict({"features": {"low_light": {key: value}}})
    assert "low_light" in str(info.value)


def test_tracker_runs_a_dark_loop_with_gamma(tmp_path):
    """A dark (light 0.15) simulated loop tracked with the gamma stage: every frame posed, the
    stage applied to every frame (their left means are below the gate)."""
    from slslam.datasets import EurocSequence
    from slslam.sim import SimOptions, Simulator
    from slslam.tracking import Tracker

    out = tmp_path / "loop"
    Simulator(SimOptions(preset="loop", frames=12, light=0.15, lidar=False)).write(
        out, progress=False
    )
    sequence = EurocSequence(out)
    means = [float(f.left.mean()) for f in sequence]
    config = config_from_dict({"features": {"low_light": {"mode": "gamma"}}})
    with Tracker(sequence.camera, config) as tracker:
        states = [tracker.track(f.left, f.right, f.t_ns * 1e-9).state for f in sequence]
        applied = tracker._low_light.applied
    assert set(states) == {"OK"}, states
    assert applied == sum(m < 60.0 for m in means) > 0, means
