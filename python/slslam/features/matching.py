"""The C++ core's keypoint tools the tracker uses, for use on their own: the per-cell limit,
descriptor matching (brute force and window-guided), the tracker's stereo matching, the
dynamic-cell filter and a RANSAC PnP prediction.

Each function converts its arrays (contiguous, the dtype the core takes) and returns numpy
arrays; the options are the core's option classes (``options.check()`` says what is out of
range), re-exported here.

    from slslam.features import GridLimitOptions, grid_limit, match_descriptors

    keep = grid_limit(kp.uv, kp.scores, width, height)       # indices, best per cell
    pairs = match_descriptors(kp_a.descriptors, kp_b.descriptors)  # (N, 2) query, train
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from slslam import _core

if TYPE_CHECKING:
    from slslam.datasets.euroc import RectifiedStereoCamera

#: The core's classes, as they are (typed in ``slslam/_core.pyi``).
GridLimitOptions = _core.GridLimitOptions
MatchOptions = _core.MatchOptions
GuidedMatchOptions = _core.GuidedMatchOptions
StereoMatchOptions = _core.StereoMatchOptions
DynamicCellOptions = _core.DynamicCellOptions
DynamicCellFilter = _core.DynamicCellFilter
PinholeCamera = _core.PinholeCamera
StereoRig = _core.StereoRig

__all__ = [
    "DynamicCellFilter",
    "DynamicCellOptions",
    "GridLimitOptions",
    "GuidedMatchOptions",
    "MatchOptions",
    "PinholeCamera",
    "RobustPrediction",
    "StereoMatchOptions",
    "StereoRig",
    "grid_limit",
    "guided_match",
    "match_descriptors",
    "match_stereo_points",
    "predict_with_robust_pose",
    "stereo_rig",
]


def _uv(uv: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(uv, dtype=np.float32).reshape(-1, 2)


def _descriptors(descriptors: np.ndarray) -> np.ndarray:
    """uint8 (binary, Hamming distance) or float32 (L2) rows, as the core matches them."""
    descriptors = np.asarray(descriptors)
    if descriptors.dtype != np.uint8:
        descriptors = descriptors.astype(np.float32, copy=False)
    return np.ascontiguousarray(descriptors)


def stereo_rig(camera: RectifiedStereoCamera) -> StereoRig:
    """The core's stereo rig (left pinhole intrinsics and baseline) of a rectified camera
    (``EurocSequence.camera``, ``KittiSequence.camera``)."""
    pinhole = _core.PinholeCamera(
        camera.fx, camera.fy, camera.cx, camera.cy, camera.width, camera.height
    )
    return _core.StereoRig(pinhole, camera.baseline_m)


def grid_limit(
    uv: np.ndarray,
    scores: np.ndarray,
    width: int,
    height: int,
    options: GridLimitOptions | None = None,
) -> np.ndarray:
    """The per-cell keypoint limit (``features.grid``): indices (ascending, int64) of the
    keypoints kept, the best ``options.max_per_cell`` by score in every ``cell_size_px`` cell of
    a ``width`` x ``height`` image (with ``strong_score``, a cell holding a keypoint at that
    score keeps only such). ``uv`` (N, 2) pixels, ``scores`` (N,)."""
    uv = _uv(uv)
    scores = np.ascontiguousarray(scores, dtype=np.float32).reshape(-1)
    if len(scores) != len(uv):
        raise ValueError(f"{len(uv)} keypoints need {len(uv)} scores, got {len(scores)}")
    if options is None:
        keep = _core.grid_limit(uv, scores, int(width), int(height))
    else:
        keep = _core.grid_limit(uv, scores, int(width), int(height), options)
    return np.asarray(keep, dtype=np.int64)


def match_descriptors(
    query: np.ndarray, train: np.ndarray, options: MatchOptions | None = None
) -> np.ndarray:
    """Brute-force matching: mutual nearest neighbours (``options.mutual``) passing the ratio
    test and ``max_distance`` (Hamming for uint8 rows, L2 for float). Returns (N, 2) int32
    (query index, train index) pairs."""
    query, train = _descriptors(query), _descriptors(train)
    if options is None:
        pairs = _core.match_descriptors(query, train)
    else:
        pairs = _core.match_descriptors(query, train, options)
    return np.asarray(pairs, dtype=np.int32).reshape(-1, 2)


def guided_match(
    predicted: np.ndarray,
    query: np.ndarray,
    keypoints: np.ndarray,
    train: np.ndarray,
    options: GuidedMatchOptions | None = None,
) -> np.ndarray:
    """Window-guided matching: for each predicted pixel (M, 2) with its descriptor (``query``
    rows), the index of the best of ``keypoints`` (K, 2, descriptors ``train``) within
    ``options.radius_px``, or -1. Returns (M,) int32."""
    args = (_uv(predicted), _descriptors(query), _uv(keypoints), _descriptors(train))
    index = _core.guided_match(*args) if options is None else _core.guided_match(*args, options)
    return np.asarray(index, dtype=np.int32).reshape(-1)


def match_stereo_points(
    left_image: np.ndarray,
    right_image: np.ndarray,
    left_uv: np.ndarray,
    left_descriptors: np.ndarray,
    right_uv: np.ndarray,
    right_descriptors: np.ndarray,
    rig: StereoRig | RectifiedStereoCamera,
    options: StereoMatchOptions | None = None,
    denoise_above_noise: float = 6.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The tracker's stereo matching of the left keypoints on a rectified uint8 pair (smoothed
    first as the tracker smooths it when noisier than ``denoise_above_noise``; 0: never):
    descriptors along the row band, then, with ``options.row_search``, each unmatched keypoint's
    patch searched along its right row (the right keypoints may then be empty), then subpixel
    refinement. ``rig``: the core's rig or a rectified camera. Returns (u_right, depth [m]),
    (N,) float64 each, -1 where unmatched."""
    if not isinstance(rig, _core.StereoRig):
        rig = stereo_rig(rig)
    options = options if options is not None else _core.StereoMatchOptions()
    u_right, depth = _core.match_stereo_points(
        np.ascontiguousarray(left_image),
        np.ascontiguousarray(right_image),
        _uv(left_uv),
        _descriptors(left_descriptors),
        _uv(right_uv),
        _descriptors(right_descriptors),
        rig,
        options,
        float(denoise_above_noise),
    )
    return np.asarray(u_right).reshape(-1), np.asarray(depth).reshape(-1)


class RobustPrediction(NamedTuple):
    """:func:`predict_with_robust_pose`'s result."""

    ok: bool  #: a pose was found
    predicted_uv: np.ndarray  #: (N, 2) float32 pixels of the points at that pose
    T_cur_prev: np.ndarray  #: (4, 4) pose of the previous camera in the current one
    inliers: np.ndarray  #: (N,) bool, the RANSAC inliers


def predict_with_robust_pose(
    points_prev: np.ndarray,
    observed: np.ndarray,
    camera: PinholeCamera,
    threshold_px: float = 2.0,
) -> RobustPrediction:
    """A RANSAC PnP pose from 3-D points (N, 3) in the previous camera's frame and their pixels
    (N, 2) in the current image (``camera``: its pinhole intrinsics), and the points' pixels at
    that pose: the prediction the dynamic-cell filter (:class:`DynamicCellFilter`, ``update``)
    compares observed positions with."""
    ok, predicted, T_cur_prev, inliers = _core.predict_with_robust_pose(
        np.ascontiguousarray(points_prev, dtype=np.float64).reshape(-1, 3),
        _uv(observed),
        camera,
        float(threshold_px),
    )
    return RobustPrediction(
        bool(ok),
        np.asarray(predicted, dtype=np.float32).reshape(-1, 2),
        np.asarray(T_cur_prev, dtype=np.float64),
        np.asarray(inliers, dtype=bool).reshape(-1),
    )
