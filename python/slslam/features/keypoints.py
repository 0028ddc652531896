"""The keypoint record every point front end returns (SuperPoint, ORB)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Keypoints:
    """Keypoints of one image.

    Attributes:
        uv: (N, 2) float32 pixel positions, u = column, v = row (pixel centres at integers).
        scores: (N,) float32 detector confidence, larger is stronger.
        descriptors: (N, D) float32 unit vectors (SuperPoint, D = 256) or uint8 bytes (ORB, 32).
    """

    uv: np.ndarray
    scores: np.ndarray
    descriptors: np.ndarray

    def __len__(self) -> int:
        return len(self.uv)

    def select(self, index: np.ndarray) -> Keypoints:
        """A subset (index array or boolean mask), in the given order."""
        return Keypoints(self.uv[index], self.scores[index], self.descriptors[index])


def check_gray_image(image: np.ndarray, min_size: int = 16) -> np.ndarray:
    """Validate a uint8 H x W image; raise ValueError with the reason otherwise."""
    if not isinstance(image, np.ndarray):
        raise ValueError(f"image must be a numpy array, got {type(image).__name__}")
    if image.ndim != 2:
        raise ValueError(f"image must be 2-D (H x W gray), got shape {image.shape}")
    if image.dtype != np.uint8:
        raise ValueError(f"image must be uint8, got {image.dtype}")
    if min(image.shape) < min_size:
        raise ValueError(f"image {image.shape[1]}x{image.shape[0]} is smaller than {min_size} px")
    return np.ascontiguousarray(image)


def smoothed_already(denoised_above_noise: float | None, above_noise: float) -> bool:
    """Whether a front end that smooths images noisier than ``above_noise`` may skip its noise
    check on an image that came through ``_core.smooth_if_noisy`` at ``denoised_above_noise``
    (None: it did not; the tracker's smoothing): when that threshold is positive and at most its
    own, an image left alone there is quiet enough for the front end too."""
    return denoised_above_noise is not None and 0.0 < denoised_above_noise <= above_noise
