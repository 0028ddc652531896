"""XFeat on noisy (dark, high-gain) frames: Immerkaer's noise estimate and the smoothing the
network sees above ``denoise_above_noise``."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

from slslam.config import ConfigError, config_from_dict
from slslam.features.xfeat import XFeat, XFeatOptions, denoise, estimate_noise


def wall(noise_sigma: float, seed: int = 0) -> np.ndarray:
    """Smooth structure (blobs of 4-12 px) plus white noise of the given sigma [gray levels]."""
    rng = np.random.default_rng(seed)
    base = sum(gaussian_filter(rng.normal(0, 1, (480, 752)), s) * s for s in (4.0, 12.0))
    base = 40 + (base - base.min()) / np.ptp(base) * 120
    return np.clip(base + rng.normal(0, noise_sigma, base.shape), 0, 255).astype(np.uint8)


@pytest.mark.parametrize("sigma", [3.0, 9.0, 15.0])
def test_noise_estimate_recovers_the_added_noise(sigma):
    # Rounding to gray levels adds about 0.3; the structure adds a little: within 15 %.
    assert estimate_noise(wall(sigma)) == pytest.approx(sigma, rel=0.15)


def test_smoothing_only_above_the_bound_and_it_lowers_the_noise():
    quiet, noisy = wall(3.0), wall(9.0)
    assert denoise(quiet, 6.0) is quiet  # below the bound: the image itself
    assert denoise(noisy, 0.0) is noisy  # 0: off
    smoothed = denoise(noisy, 6.0)
    assert smoothed.shape == noisy.shape and smoothed.dtype == np.uint8
    assert estimate_noise(smoothed) < 0.5 * estimate_noise(noisy)


def test_detector_sees_the_smoothed_image_only_when_the_frame_is_noisy():
    # The accuracy gain is measured on whole runs (benchmarks/log/realtime.md); here the
    # wiring: keypoints at their own pixels, descriptors of the smoothed input.
    on, off = (
        XFeat(XFeatOptions(denoise_above_noise=6.0)),
        XFeat(XFeatOptions(denoise_above_noise=0)),
    )
    noisy, quiet = wall(9.0), wall(3.0)
    a, b = on.detect(noisy), off.detect(denoise(noisy, 6.0))
    assert len(a) > 50 and np.array_equal(a.uv, b.uv)
    assert np.array_equal(a.descriptors, b.descriptors)
    assert not np.array_equal(a.uv, off.detect(noisy).uv)
    assert np.array_equal(on.detect(quiet).uv, off.detect(quiet).uv)


def test_an_image_the_tracker_smoothed_is_not_checked_again():
    """``denoised_above_noise`` (the tracker's threshold): the image came through the tracker's
    smoothing, so XFeat's own check is skipped at its threshold or below; the same keypoints."""
    xfeat = XFeat(XFeatOptions(denoise_above_noise=6.0))
    noisy = wall(9.0)
    smoothed = denoise(noisy, 6.0)
    a, b = xfeat.detect(smoothed), xfeat.detect(smoothed, denoised_above_noise=6.0)
    assert len(a) > 50 and np.array_equal(a.uv, b.uv)
    assert np.array_equal(a.descriptors, b.descriptors)
    # told so of a raw noisy image, XFeat believes it; above its threshold it checks anyway
    assert not np.array_equal(xfeat.detect(noisy, denoised_above_noise=6.0).uv, a.uv)
    assert np.array_equal(xfeat.detect(noisy, denoised_above_noise=8.0).uv, a.uv)


def test_bad_bound_is_a_config_error_naming_the_key():
    with pytest.raises(ConfigError, match="denoise_above_noise"):
        config_from_dict({"features": {"xfeat": {"denoise_above_noise": -1.0}}})
