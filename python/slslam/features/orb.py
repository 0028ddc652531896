"""ORB (OpenCV, in the C++ core) behind the same interface as SuperPoint: the baseline."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slslam import _core
from slslam._cpp_defaults import as_written
from slslam.features.keypoints import Keypoints, check_gray_image, smoothed_already

_CORE_ORB = _core.OrbOptions()


@dataclass(frozen=True)
class OrbOptions:
    """ORB settings (OpenCV's ORB; ORB-SLAM-like defaults)."""

    # Defaults: the C++ OrbOptions' (the one place they are written).
    max_keypoints: int = _CORE_ORB.max_features
    scale_factor: float = as_written(_CORE_ORB.scale_factor)  # pyramid scale between levels [-]
    num_levels: int = _CORE_ORB.num_levels
    fast_threshold: int = _CORE_ORB.fast_threshold  # [gray levels]


class Orb:
    """``detect(image)`` returns :class:`Keypoints` with uint8 (N, 32) descriptors."""

    #: The tracker hands ORB the pair it smoothed when noisy (``tracking.denoise_above_noise``):
    #: ORB would smooth a noisy image itself the same way, so this saves that second blur.
    smoothed_input = True
    # Its detect's keywords (slslam.features.PointFrontEnd): denoised_above_noise only (ORB's
    # adaptive FAST threshold is its own low-texture fallback; the tracker limits per cell after).
    detect_takes_threshold = False
    detect_takes_select = False
    detect_takes_denoised = True

    def __init__(self, options: OrbOptions = OrbOptions(), adaptive: bool = True):
        """``adaptive``: per-cell FAST threshold fallback (20 -> 7 in cells without a corner at
        the normal threshold, as ORB-SLAM); False: OpenCV's plain ORB detection."""
        self.options = options
        self._core_options = self._make_core_options(adaptive)
        # The same without ORB's own noise check (detect's denoised_above_noise).
        self._checked_options = self._make_core_options(adaptive)
        self._checked_options.denoise_above_noise = 0.0

    def _make_core_options(self, adaptive: bool) -> _core.OrbOptions:
        core = _core.OrbOptions()
        core.max_features = self.options.max_keypoints
        core.scale_factor = self.options.scale_factor
        core.num_levels = self.options.num_levels
        core.fast_threshold = self.options.fast_threshold
        core.adaptive = adaptive
        core.min_fast_threshold = min(core.min_fast_threshold, self.options.fast_threshold)
        core.check()
        return core

    def detect(self, image: np.ndarray, denoised_above_noise: float | None = None) -> Keypoints:
        """Keypoints of one uint8 gray image. ``denoised_above_noise``: the image came through
        ``_core.smooth_if_noisy`` at this threshold (the tracker smooths each image once for all
        its steps); ORB's own check, which smooths an image noisier than its threshold the same
        way, is then skipped when that threshold is at least this one (an image left alone there
        is quiet enough for it): 0.1 ms less a 752 x 480 image, and the same keypoints whenever
        one blur leaves the image quiet (a pattern whose estimate stays above the threshold after
        one blur would otherwise be blurred a second time)."""
        options = self._core_options
        if smoothed_already(denoised_above_noise, options.denoise_above_noise):
            options = self._checked_options
        uv, score, descriptors = _core.extract_orb(check_gray_image(image), options)
        return Keypoints(uv.astype(np.float32), score.astype(np.float32), descriptors)
