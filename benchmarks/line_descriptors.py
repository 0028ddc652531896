"""Line descriptors side by side: OpenCV's BinaryDescriptor (opencv_lbd) and ours (lbd).

    python benchmarks/line_descriptors.py [--seed 11] [--frames 300] [--gap 3] [--out FILE]

Both describe the same segments: the tracker's line front end (LSD on the half-size image, the
150 longest after preprocessing), on simulated frames (the loop at light 1.0, the loop at 0.15
with dust, the junction at 0.15 with dust) every 30 frames, each against the frame --gap later. A
pair of segments (a, b) is a true match when a's endpoints, moved into the later frame through
the simulator's depth and poses, lie within 3 px of b's line and overlap it (line_frontend.py's
test). Per descriptor:

* local choice: for each segment with at least two candidates near its true position (midpoint
  within 20 px, angle within 0.2 rad, as the tracker's projection search) and a true one among
  them, is the nearest candidate by Hamming distance a true match;
* distances: the share of true / false pairs within 60 and 80 bits (the tracker's bounds), and
  the share of true pairs found at the distance that lets 4.5 % of the false ones pass;
* time per image of the whole line front end (median).

Our bits were chosen on frames of seed 5 (features/lbd.cpp); the default seed 11 is held out.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from slslam import _core
from slslam.sim import SimOptions, Simulator

from common import segment_match_correct, sim_cam_b_from_cam_a, transfer_pixels, write_results

EPS_PX = 3.0
SCENES = (("loop", 1.0, False), ("loop", 0.15, True), ("junction", 0.15, True))
DESCRIPTORS = ("opencv_lbd", "lbd")


def _angles(s: np.ndarray) -> np.ndarray:
    return np.arctan2(s[:, 3] - s[:, 1], s[:, 2] - s[:, 0])


def pairs_of(seed: int, frames: int, gap: int) -> list:
    out = []
    for preset, light, dust in SCENES:
        sim = Simulator(SimOptions(preset=preset, frames=frames, light=light, seed=seed, dust=dust))
        cam = sim.camera
        for a in range(35, frames - gap, 30):
            b = a + gap
            img_a, _, depth_a = sim.render_stereo(a)
            img_b, _, _ = sim.render_stereo(b)
            T_b_a = sim_cam_b_from_cam_a(sim, a, b)

            def transfer(uv, depth_a=depth_a, T_b_a=T_b_a, cam=cam):
                return transfer_pixels(uv, depth_a, T_b_a, cam)[0]

            out.append((f"{preset} {light}", img_a, img_b, transfer))
    return out


def evaluate(descriptor: str, pairs: list) -> dict:
    options = _core.LineExtractorOptions()
    options.descriptor = descriptor
    local: dict[str, list[int]] = {}
    true_d, false_d, times = [], [], []
    for scene, img_a, img_b, transfer in pairs:
        start = time.perf_counter()
        seg_a, des_a, _ = _core.extract_lines(img_a, options)
        times.append((time.perf_counter() - start) * 1e3)
        seg_b, des_b, _ = _core.extract_lines(img_b, options)
        moved = transfer(seg_a.reshape(-1, 2)).reshape(-1, 4)
        dist = np.unpackbits(np.bitwise_xor(des_a[:, None, :], des_b[None, :, :]), axis=2).sum(2)
        mid_b = 0.5 * (seg_b[:, :2] + seg_b[:, 2:])
        ang_a, ang_b = _angles(moved), _angles(seg_b)
        for i in range(len(seg_a)):
            if not np.all(np.isfinite(moved[i])):
                continue
            ok = np.array(
                [segment_match_correct(moved[i], seg_b[j], EPS_PX) for j in range(len(seg_b))],
                dtype=bool,
            )
            true_d += dist[i, ok].tolist()
            false_d += dist[i, ~ok].tolist()
            mid = 0.5 * (moved[i, :2] + moved[i, 2:])
            dang = np.abs((ang_b - ang_a[i] + np.pi / 2) % np.pi - np.pi / 2)
            near = np.where((np.linalg.norm(mid_b - mid, axis=1) < 20.0) & (dang < 0.2))[0]
            if len(near) < 2 or not ok[near].any():
                continue
            counts = local.setdefault(scene, [0, 0])
            counts[0] += 1
            counts[1] += int(ok[near[np.argmin(dist[i, near])]])
    t, f = np.asarray(true_d), np.asarray(false_d)
    at = float(np.percentile(f, 4.5))
    return {
        "local_choice": {
            k: {"cases": v[0], "right": v[1], "share": v[1] / v[0]} for k, v in local.items()
        },
        "true_within": {"60": float(np.mean(t <= 60)), "80": float(np.mean(t <= 80))},
        "false_within": {"60": float(np.mean(f <= 60)), "80": float(np.mean(f <= 80))},
        "true_median_bits": float(np.median(t)),
        "distance_at_false_4.5pct": at,
        "true_at_false_4.5pct": float(np.mean(t <= at)),
        "line_frontend_ms_median": float(np.median(times)),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=11)
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--gap", type=int, default=3, help="frames between the two of a pair")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    if args.gap < 1:
        parser.error("--gap must be >= 1")
    pairs = pairs_of(args.seed, args.frames, args.gap)
    results = {d: evaluate(d, pairs) for d in DESCRIPTORS}
    scenes = ", ".join(results["lbd"]["local_choice"])
    print(
        f"| descriptor | local choice right ({scenes}) | true / false within 60 bits | within 80 "
        "| true at 4.5 % false (bits) | line front end [ms/image] |"
    )
    print("|---|---|---|---|---|---|")
    for d, r in results.items():
        local = " / ".join(f"{v['share']:.3f}" for v in r["local_choice"].values())
        print(
            f"| {d} | {local} | {r['true_within']['60']:.3f} / {r['false_within']['60']:.3f} "
            f"| {r['true_within']['80']:.3f} / {r['false_within']['80']:.3f} "
            f"| {r['true_at_false_4.5pct']:.3f} ({r['distance_at_false_4.5pct']:.0f}) "
            f"| {r['line_frontend_ms_median']:.1f} |"
        )
    saved = {"seed": args.seed, "gap": args.gap, **results}
    print(f"wrote {write_results('line_descriptors', saved, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
