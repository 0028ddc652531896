"""Line front end through the Python bindings, checked against the simulator's exact geometry."""

from __future__ import annotations

import numpy as np
import pytest

from slslam import _core
from slslam.sim import SimOptions, Simulator


@pytest.fixture(scope="module")
def stereo_frame():
    sim = Simulator(SimOptions(preset="loop", frames=40, noise=False, seed=2))
    left, right, depth = sim.render_stereo(20)
    return sim.camera, left, right, depth


def test_stereo_line_matches_and_triangulation_agree_with_ray_cast_depth(stereo_frame):
    cam, left, right, depth = stereo_frame
    seg_l, lbd_l, raw_l = _core.extract_lines(left)
    seg_r, lbd_r, _ = _core.extract_lines(right)
    assert raw_l > len(seg_l) > 20  # preprocessing removed short and duplicate segments
    pairs = _core.match_stereo_lines(seg_l, lbd_l, seg_r, lbd_r)
    assert len(pairs) > 10

    # Ground truth: a left endpoint at depth z appears in the right image at u - fx b / z.
    def depth_at(points):
        u = np.clip(np.round(points[:, 0]).astype(int), 0, cam.width - 1)
        v = np.clip(np.round(points[:, 1]).astype(int), 0, cam.height - 1)
        return depth[v, u]

    matched_l, matched_r = seg_l[pairs[:, 0]], seg_r[pairs[:, 1]]
    ends = matched_l.reshape(-1, 2)
    truth = ends - np.column_stack([cam.fx * cam.baseline_m / depth_at(ends), np.zeros(len(ends))])
    r0, r1 = matched_r[:, :2].repeat(2, 0), matched_r[:, 2:].repeat(2, 0)
    d = (r1 - r0) / np.linalg.norm(r1 - r0, axis=1, keepdims=True)
    off_line = np.abs(d[:, 0] * (truth[:, 1] - r0[:, 1]) - d[:, 1] * (truth[:, 0] - r0[:, 0]))
    correct = off_line.reshape(-1, 2).mean(axis=1) < 3.0
    assert correct.mean() > 0.8, f"stereo line precision {correct.mean():.2f}"
    # Triangulated endpoints sit at the ray-cast depth of their left pixels (correct matches).
    pinhole = _core.PinholeCamera(cam.fx, cam.fx, cam.cx, cam.cy, cam.width, cam.height)
    points, ok = _core.triangulate_stereo_lines(matched_l, matched_r, pinhole, cam.baseline_m)
    ok = np.asarray(ok) & correct
    assert ok.sum() > 5
    z_true = depth_at(matched_l[ok].reshape(-1, 2))
    z_est = points[ok][:, [2, 5]].reshape(-1)
    relative = np.abs(z_est - z_true) / z_true
    assert np.median(relative) < 0.05


def test_association_and_point_driven_matching_run_on_real_images(stereo_frame):
    cam, left, _, _ = stereo_frame
    seg, lbd, _ = _core.extract_lines(left)
    uv, _, _ = _core.extract_orb(left)
    assoc = _core.associate_points_to_lines(uv, seg, cam.width, cam.height)
    assert len(assoc) == len(seg) and sum(len(a) for a in assoc) > 0
    # The same frame against itself: every line with a point matches itself.
    identity = np.column_stack([np.arange(len(uv)), np.arange(len(uv))]).astype(np.int32)
    pairs = _core.match_lines_by_points(seg, assoc, lbd, seg, assoc, lbd, identity)
    with_points = [i for i, a in enumerate(assoc) if len(a)]
    assert len(pairs) > 0.8 * len(with_points)
    assert np.all(pairs[:, 0] == pairs[:, 1])


def test_bad_line_inputs_raise_clear_errors():
    with pytest.raises(ValueError, match="LBD"):
        _core.match_stereo_lines(
            np.zeros((1, 4), np.float32),
            np.zeros((1, 8), np.uint8),
            np.zeros((1, 4), np.float32),
            np.zeros((1, 32), np.uint8),
        )
    with pytest.raises(ValueError, match="2-D"):
        _core.extract_lines(np.zeros((4, 4, 3), np.uint8))
    with pytest.raises(ValueError, match="image"):
        _core.detect_lsd_segments(np.zeros((4, 4), np.float32))


def _covered_fraction(a: np.ndarray, b: np.ndarray, tol_px: float = 1.0) -> float:
    """Share of the length of a's segments within tol_px of a segment of b at a similar angle."""
    total = covered = 0.0
    db = b[:, 2:] - b[:, :2]
    lb = np.linalg.norm(db, axis=1)
    ub = db / np.maximum(lb, 1e-9)[:, None]
    for s in a:
        d = s[2:] - s[:2]
        length = float(np.linalg.norm(d))
        u = d / length
        near_angle = np.abs(ub @ np.array([-u[1], u[0]])) < np.sin(np.deg2rad(5.0))
        t = np.linspace(0.0, 1.0, max(2, int(length)))
        pts = s[:2] + t[:, None] * d
        rel = pts[:, None, :] - b[None, near_angle, :2]
        along = np.clip((rel * ub[None, near_angle]).sum(-1), 0.0, lb[None, near_angle])
        off = rel - along[..., None] * ub[None, near_angle]
        dist = np.linalg.norm(off, axis=-1).min(axis=1) if near_angle.any() else np.inf
        covered += length * float(np.mean(dist <= tol_px))
        total += length
    return covered / max(total, 1e-9)


def test_our_lsd_keeps_the_lines_of_opencvs_lsd_on_a_rendered_frame(stereo_frame):
    """The tracker's lines (LSD at half size, preprocessing, LBD) with our LSD and OpenCV's."""
    _, left, _, _ = stereo_frame
    ours, theirs = _core.LineExtractorOptions(), _core.LineExtractorOptions()
    theirs.detector = "lsd_opencv"
    assert ours.detector == "lsd"
    a, _, raw_a = _core.extract_lines(left, ours)
    b, _, raw_b = _core.extract_lines(left, theirs)
    assert len(a) > 40 and abs(len(a) - len(b)) <= 0.15 * len(b)
    assert abs(raw_a - raw_b) <= 0.15 * raw_b
    assert _covered_fraction(b, a) > 0.85 and _covered_fraction(a, b) > 0.85
