"""The public wrappers of the core's keypoint tools (slslam.features.matching) give what the core
gives, and the README and docs show them rather than ``_core`` functions."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import slslam.features as features
from slslam import _core
from slslam.datasets.euroc import RectifiedStereoCamera

ROOT = Path(__file__).resolve().parents[2]


def test_readme_and_docs_name_no_core_function():
    """A user is shown public names: ``_core.X`` is left to the code (``_core.pyi`` is a file)."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    found = {
        f"{page.relative_to(ROOT)}: {name}"
        for page in pages
        for name in re.findall(r"_core\.(?!pyi\b)\w+", page.read_text(encoding="utf-8"))
    }
    assert not found


def test_the_wrappers_are_public_and_typed():
    for name in (
        "grid_limit",
        "match_descriptors",
        "guided_match",
        "match_stereo_points",
        "predict_with_robust_pose",
        "DynamicCellFilter",
        "DynamicCellOptions",
        "GridLimitOptions",
        "MatchOptions",
        "GuidedMatchOptions",
        "StereoMatchOptions",
    ):
        assert name in features.__all__
        value = getattr(features, name)
        assert value.__doc__, name
    assert features.DynamicCellFilter is _core.DynamicCellFilter


def _keypoints(seed: int, n: int = 300) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    uv = rng.uniform(0, [320, 240], (n, 2)).astype(np.float32)
    return uv, rng.uniform(0, 1, n).astype(np.float32), rng.integers(0, 256, (n, 32), np.uint8)


def test_grid_limit_and_matching_give_what_the_core_gives():
    uv, scores, descriptors = _keypoints(0)
    options = features.GridLimitOptions()
    options.max_per_cell = 2
    keep = features.grid_limit(uv.astype(np.float64), scores, 320, 240, options)
    assert keep.dtype == np.int64
    assert np.array_equal(keep, _core.grid_limit(uv, scores, 320, 240, options))
    assert np.array_equal(
        features.grid_limit(uv, scores, 320, 240), _core.grid_limit(uv, scores, 320, 240)
    )
    with pytest.raises(ValueError, match="300 keypoints need 300 scores"):
        features.grid_limit(uv, scores[:-1], 320, 240)

    noisy = descriptors.copy()
    noisy[::3, 0] ^= 0xFF  # some rows differ, most match themselves
    pairs = features.match_descriptors(descriptors, noisy)
    assert pairs.shape[1] == 2 and len(pairs) > 100
    assert np.array_equal(pairs, np.asarray(_core.match_descriptors(descriptors, noisy)))

    predicted = uv + 1.0
    index = features.guided_match(predicted, descriptors, uv, descriptors)
    assert index.shape == (len(uv),)
    core = np.asarray(_core.guided_match(predicted, descriptors, uv, descriptors)).reshape(-1)
    assert np.array_equal(index, core)
    assert np.mean(index == np.arange(len(uv))) > 0.9


def test_match_stereo_points_takes_a_camera_or_a_rig():
    rng = np.random.default_rng(0)
    texture = rng.uniform(0, 255, (240, 336)).astype(np.uint8)
    left, right = np.ascontiguousarray(texture[:, :320]), np.ascontiguousarray(texture[:, 8:328])
    v, u = np.mgrid[20:220:20, 40:300:20]
    uv = np.stack([u.ravel(), v.ravel()], axis=1).astype(np.float32)
    descriptors = np.zeros((len(uv), 32), np.uint8)
    camera = RectifiedStereoCamera(300.0, 300.0, 159.5, 119.5, 320, 240, 0.1, np.eye(4))
    options = features.StereoMatchOptions()
    options.row_search = True
    args = (left, right, uv, descriptors, uv[:0], descriptors[:0])
    u_right, depth = features.match_stereo_points(*args, camera, options, 0.0)
    rig = features.stereo_rig(camera)
    u_core, depth_core = _core.match_stereo_points(*args, rig, options, 0.0)
    assert u_right.shape == depth.shape == (len(uv),)
    assert np.array_equal(u_right, np.asarray(u_core).ravel())
    assert np.array_equal(depth, np.asarray(depth_core).ravel())
    assert np.array_equal(features.match_stereo_points(*args, rig, options, 0.0)[1], depth)
    found = depth > 0
    assert found.mean() > 0.8
    assert np.allclose(uv[found, 0] - u_right[found], 8.0, atol=0.5)


def test_predict_with_robust_pose_finds_the_motion():
    rng = np.random.default_rng(1)
    camera = features.PinholeCamera(300.0, 300.0, 160.0, 120.0, 320, 240)
    points = np.column_stack([rng.uniform(-2, 2, (200, 2)), rng.uniform(3, 8, 200)])
    T_cur_prev = np.eye(4)
    T_cur_prev[:3, 3] = [0.1, 0.0, -0.05]
    moved = points + T_cur_prev[:3, 3]
    observed = (300.0 * moved[:, :2] / moved[:, 2:] + [160.0, 120.0]).astype(np.float32)
    prediction = features.predict_with_robust_pose(points, observed, camera)
    assert isinstance(prediction, features.RobustPrediction)
    ok, predicted_uv, T, inliers = prediction
    assert ok and inliers.dtype == bool and inliers.mean() > 0.9
    assert predicted_uv.shape == (200, 2)
    assert np.allclose(T, T_cur_prev, atol=1e-3)
    assert np.allclose(predicted_uv, observed, atol=0.1)
