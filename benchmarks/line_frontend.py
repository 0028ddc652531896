"""Line front end: point-driven line matching vs brute-force LBD matching, side by side.

    python benchmarks/line_frontend.py [--out FILE] [--figures DIR]

On simulated mine frames (loop, light 1.0 and 0.15, pairs 10 frames = 0.5 s apart) and on the real
EuRoC excerpt (rectified; the camera stands still there, so the true transfer is the identity),
reports: LSD segments before / after preprocessing, point-line associations, and for each matcher
the number of line matches, their precision and the time. A line match (a, b) is correct when a's
endpoints, transferred into B (ray-cast depth and true pose for the simulator), lie within
EPS_PX of b's line on average and the transferred segment overlaps b along the line.
Point matches (the input of point-driven matching) come from SuperPoint when weights are found
($SLSLAM_SUPERPOINT_MODEL, else the workplace copy in ../shared/models), as in the paper, and from
ORB with --orb or without weights.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from slslam import _core
from slslam.datasets import EurocSequence
from slslam.features.orb import Orb
from slslam.sim import SimOptions, Simulator

from common import (
    SHARED_DATA,
    segment_match_correct,
    sim_cam_b_from_cam_a,
    transfer_pixels,
    write_results,
)

EPS_PX = 3.0


def _timed(fn, repeats: int = 5):
    fn()
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        samples.append((time.perf_counter() - start) * 1e3)
    return out, float(np.median(samples))


def _precision(pairs: np.ndarray, seg_a: np.ndarray, seg_b: np.ndarray, transfer) -> float:
    if len(pairs) == 0:
        return float("nan")
    moved = transfer(seg_a[pairs[:, 0]].reshape(-1, 2)).reshape(-1, 4)
    return float(
        np.mean(
            [
                segment_match_correct(m, seg_b[j], EPS_PX)
                for m, j in zip(moved, pairs[:, 1], strict=True)
            ]
        )
    )


def full_resolution_lines() -> _core.LineExtractorOptions:
    """The paper's extractor: LSD at full resolution, every segment preprocessing keeps (the
    numbers this script prints; the tracker's defaults detect at half resolution and keep
    the 150 longest)."""
    options = _core.LineExtractorOptions()
    options.detection_scale = 1.0
    options.max_lines = 0
    return options


def evaluate_pair(img_a, img_b, transfer, points, figure: Path | None = None) -> dict:
    h, w = img_a.shape
    seg_a, lbd_a, raw_a = _core.extract_lines(img_a, full_resolution_lines())
    seg_b, lbd_b, raw_b = _core.extract_lines(img_b, full_resolution_lines())
    kp_a, kp_b = points.detect(img_a), points.detect(img_b)
    match_options = _core.MatchOptions()
    if kp_a.descriptors.dtype == np.uint8:
        match_options.max_distance = 64.0
    else:
        match_options.max_distance = 1.0
    point_pairs = _core.match_descriptors(kp_a.descriptors, kp_b.descriptors, match_options)
    (assoc_a, assoc_b), t_assoc = _timed(
        lambda: (
            _core.associate_points_to_lines(kp_a.uv, seg_a, w, h),
            _core.associate_points_to_lines(kp_b.uv, seg_b, w, h),
        )
    )
    driven, t_driven = _timed(
        lambda: _core.match_lines_by_points(
            seg_a, assoc_a, lbd_a, seg_b, assoc_b, lbd_b, point_pairs
        )
    )
    brute_options = _core.MatchOptions()
    brute_options.max_distance = 80.0
    brute, t_brute = _timed(lambda: _core.match_descriptors(lbd_a, lbd_b, brute_options))
    if figure is not None:
        from slslam.viz import draw_matches

        draw_matches(
            figure,
            img_a,
            img_b,
            kp_a.uv,
            kp_b.uv,
            point_pairs,
            seg_a,
            seg_b,
            driven,
            title="point matches (green) and point-driven line matches",
        )
    return {
        "lsd_segments": [raw_a, raw_b],
        "after_preprocessing": [len(seg_a), len(seg_b)],
        "lines_with_points": [
            int(sum(len(x) > 0 for x in assoc_a)),
            int(sum(len(x) > 0 for x in assoc_b)),
        ],
        "associations": [int(sum(len(x) for x in assoc_a)), int(sum(len(x) for x in assoc_b))],
        "point_matches": len(point_pairs),
        "point_driven": {
            "matches": len(driven),
            "precision": _precision(driven, seg_a, seg_b, transfer),
            "match_ms": t_driven,
            "association_ms": t_assoc,
        },
        "brute_force_lbd": {
            "matches": len(brute),
            "precision": _precision(brute, seg_a, seg_b, transfer),
            "match_ms": t_brute,
        },
    }


def _depth_transfer(depth_a, T_b_a, cam):
    return lambda uv: transfer_pixels(uv, depth_a, T_b_a, cam)[0]


def simulated(points, figures: Path | None) -> dict:
    out = {}
    for light in (1.0, 0.15):
        sim = Simulator(SimOptions(preset="loop", frames=120, light=light, seed=5))
        cam = sim.camera
        rows = []
        for a in (20, 60, 100):
            b = a + 10
            img_a, _, depth_a = sim.render_stereo(a)
            img_b, _, _ = sim.render_stereo(b)
            transfer = _depth_transfer(depth_a, sim_cam_b_from_cam_a(sim, a, b), cam)
            fig = None if figures is None else figures / f"sim_light{light}_{a}_{b}.png"
            rows.append(evaluate_pair(img_a, img_b, transfer, points, fig))
        out[f"sim_light{light}"] = rows
    return out


def euroc(points, figures: Path | None) -> dict:
    data = SHARED_DATA / "euroc_v101_micro"
    if not data.exists():
        return {"skipped": f"{data} not available"}
    seq = EurocSequence(data)
    rows = []
    for a, b in ((0, 10), (40, 50), (80, 90)):
        fig = None if figures is None else figures / f"euroc_{a}_{b}.png"
        rows.append(evaluate_pair(seq[a].left, seq[b].left, lambda uv: uv, points, fig))
    return {"euroc_v101_static": rows}


def _summary(name: str, rows: list[dict]) -> None:
    def mean(key, sub=None):
        vals = [r[key][sub] if sub else r[key] for r in rows]
        vals = [np.mean(v) if isinstance(v, list) else v for v in vals]
        return float(np.nanmean(vals))

    print(
        f"{name}: LSD {mean('lsd_segments'):.0f} -> {mean('after_preprocessing'):.0f} lines, "
        f"{mean('lines_with_points'):.0f} with points, {mean('associations'):.0f} associations, "
        f"{mean('point_matches'):.0f} point matches"
    )
    for method in ("point_driven", "brute_force_lbd"):
        extra = (
            f" (+ association {mean(method, 'association_ms'):.2f} ms)"
            if method == "point_driven"
            else ""
        )
        print(
            f"  {method:16s} matches {mean(method, 'matches'):6.1f}  precision "
            f"{mean(method, 'precision'):.3f}  time {mean(method, 'match_ms'):.3f} ms{extra}"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--figures", type=Path, default=None, help="write match pictures here")
    parser.add_argument("--orb", action="store_true", help="ORB point matches instead")
    args = parser.parse_args()
    model = os.environ.get("SLSLAM_SUPERPOINT_MODEL") or str(
        SHARED_DATA.parent / "models" / "superpoint_v1" / "superpoint_v1.onnx"
    )
    points = Orb()
    if not args.orb and Path(model).is_file():
        from slslam.features import SuperPoint, SuperPointOptions

        points = SuperPoint(SuperPointOptions(model_path=model, max_keypoints=1000))
    elif not args.orb:
        print("SuperPoint weights not found: ORB point matches")
    results = {
        "eps_px": EPS_PX,
        "points": type(points).__name__,
        **simulated(points, args.figures),
        **euroc(points, args.figures),
    }
    for name, rows in results.items():
        if isinstance(rows, list):
            _summary(name, rows)
    print(f"wrote {write_results('line_frontend', results, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
