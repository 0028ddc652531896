"""ORB (OpenCV, in the C++ core) behind the same interface as SuperPoint: the baseline."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slslam import _core
from slslam._cpp_defaults import as_written
from slslam.features.keypoints import Keypoints, check_gray_image

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

    def __init__(self, options: OrbOptions = OrbOptions(), adaptive: bool = True):
        """``adaptive``: per-cell FAST threshold fallback (20 -> 7 in cells without a corner at
        the normal threshold, as ORB-SLAM); False: OpenCV's plain ORB detection."""
        self.options = options
        self._core_options = _core.OrbOptions()
        self._core_options.max_features = options.max_keypoints
        self._core_options.scale_factor = options.scale_factor
        self._core_options.num_levels = options.num_levels
        self._core_options.fast_threshold = options.fast_threshold
        self._core_options.adaptive = adaptive
        self._core_options.min_fast_threshold = min(
            self._core_options.min_fast_threshold, options.fast_threshold
        )
        self._core_options.check()

    def detect(self, image: np.ndarray) -> Keypoints:
        uv, score, descriptors = _core.extract_orb(check_gray_image(image), self._core_options)
        return Keypoints(uv.astype(np.float32), score.astype(np.float32), descriptors)
