"""Low-light enhancement of a stereo pair before the front end (SL-SLAM's stated future work).

Two modes, none unless ``features.low_light.mode`` names one:

``gamma``
    One tone curve ``out = 255 * (in / 255) ** gamma`` for both images of the pair, with gamma
    chosen from the left image so that its mean gray level maps to ``target_mean_gray``; applied
    only when that mean is below ``below_mean_gray``, and gamma never below ``min_gamma`` (a
    stronger curve mostly amplifies the sensor's noise). The same curve on both images keeps
    the left and right intensities comparable for the stereo row search.
``clahe``
    OpenCV's contrast-limited adaptive histogram equalisation on each image (tiles of
    ``clahe_tile_px`` pixels, clip limit ``clahe_clip_limit``), under the same darkness gate.

The pair is enhanced as it enters the tracker, before the noisy-frame smoothing
(``tracking.denoise_above_noise``): the noise a curve amplifies is then smoothed as the sensor's
own would be. The per-pixel work is OpenCV's (``cv2.LUT``, ``cv2.createCLAHE``); gamma's
256-entry table is built per frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

if TYPE_CHECKING:
    import cv2

LowLightMode = Literal["none", "gamma", "clahe"]
LOW_LIGHT_MODES: tuple[str, ...] = ("none", "gamma", "clahe")


@dataclass(frozen=True)
class LowLightOptions:
    """How dark frames are enhanced before the front end (``features.low_light``)."""

    mode: LowLightMode = "none"  # none | gamma | clahe
    below_mean_gray: float = 60.0  # enhance only frames whose left mean is below this [gray]
    target_mean_gray: float = 100.0  # gamma: the left image's mean maps to this [gray]
    min_gamma: float = 0.4  # gamma: the strongest curve allowed [-]
    clahe_clip_limit: float = 2.0  # clahe: OpenCV's clip limit [-]
    clahe_tile_px: int = 64  # clahe: side of a tile [px] (tiles follow the image size)

    def check(self) -> None:
        """ValueError naming the first option out of range."""
        if self.mode not in LOW_LIGHT_MODES:
            raise ValueError(f"mode must be one of {LOW_LIGHT_MODES}, got {self.mode!r}")
        for name, low, high in (
            ("below_mean_gray", 0.0, 255.0),
            ("target_mean_gray", 1.0, 254.0),
            ("min_gamma", 0.05, 1.0),
            ("clahe_clip_limit", 0.1, 100.0),
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"{name} must be a number, got {value!r}")
            if not (math.isfinite(value) and low <= value <= high):
                raise ValueError(f"{name} must be in [{low:g}, {high:g}], got {value!r}")
        tile = self.clahe_tile_px
        if isinstance(tile, bool) or not isinstance(tile, int) or not 8 <= tile <= 4096:
            raise ValueError(f"clahe_tile_px must be an integer in [8, 4096], got {tile!r}")


class LowLightEnhancer:
    """``enhancer.pair(left, right)`` -> the pair as the front end gets it (the same arrays when
    the frame is bright enough or the mode is none); ``enhancer.applied`` counts enhanced pairs."""

    def __init__(self, options: LowLightOptions = LowLightOptions()):
        options.check()
        self.options = options
        self.applied = 0
        self._clahe: cv2.CLAHE | None = None

    @property
    def enabled(self) -> bool:
        return self.options.mode != "none"

    def gamma_for(self, mean_gray: float) -> float | None:
        """The gamma a left image of this mean gets; None: left as it is."""
        o = self.options
        if o.mode != "gamma" or mean_gray >= o.below_mean_gray or mean_gray >= o.target_mean_gray:
            return None
        mean = max(mean_gray, 0.5) / 255.0
        return max(o.min_gamma, math.log(o.target_mean_gray / 255.0) / math.log(mean))

    def pair(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        import cv2  # opencv-python-headless

        o = self.options
        if o.mode == "none":
            return left, right
        mean = float(cv2.mean(left)[0])
        if mean >= o.below_mean_gray:
            return left, right
        if o.mode == "gamma":
            gamma = self.gamma_for(mean)
            if gamma is None:
                return left, right
            lut = np.clip(np.round(255.0 * (np.arange(256) / 255.0) ** gamma), 0, 255).astype(
                np.uint8
            )
            self.applied += 1
            return cv2.LUT(left, lut), cv2.LUT(right, lut)
        if self._clahe is None or self._clahe_size != left.shape:
            tiles = (
                max(1, round(left.shape[1] / o.clahe_tile_px)),
                max(1, round(left.shape[0] / o.clahe_tile_px)),
            )
            self._clahe = cv2.createCLAHE(clipLimit=o.clahe_clip_limit, tileGridSize=tiles)
            self._clahe_size: tuple[int, ...] = left.shape
        self.applied += 1
        return self._clahe.apply(left), self._clahe.apply(right)
