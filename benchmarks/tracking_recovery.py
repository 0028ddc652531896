"""Holding on and coming back: the tracker on simulated hard cases (issue 13's measurements).

    python benchmarks/tracking_recovery.py [--sequences loop_l100 loop_l015_dust junction_hard
        junction_spin] [--configs orb_lines,orb_lines_plain,orb] [--frames 600]
        [--data-dir DIR] [--out DIR] [--set tracking.KEY=VALUE ...]

Sequences (seed 0, no LiDAR, simulated once into --data-dir): the loop at light 1.0
(loop_l100) and at 0.15 with dust (loop_l015_dust); the junction at 0.15 with dust, exposure
flicker and a 1 s headlamp blackout (junction_hard); the junction at light 0.5 with a 360 degree
turn on the spot at t = 10 s (junction_spin, when the simulator offers ``spin_at_s``).
Configurations: ORB + lines with the defaults (orb_lines); XFeat + lines from configs/xfeat.yaml
(xfeat_lines); ORB + lines with the low-texture fallback off, i.e. plain OpenCV ORB detection as
before it (orb_lines_plain); ORB points only (orb).

Per run: frames with an estimated pose after the first initialisation (OK, RELOCALISED, NEW_MAP,
INERTIAL), relocalisations, new maps after a loss, frames the IMU bridged (the simulator writes
imu0/, used by default; ``--set tracking.imu.enabled=false`` for camera only), frames and
seconds without an estimate, maps, ATE RMSE over every estimated frame (evo, SE3 alignment of
the whole run) in metres and as a share of the path driven, median keypoints per frame (whole
run and over the frames whose inliers were lowest, the hard stretch), keyframes and median time
per frame. Writes tracking_recovery.md and .json in --out and each run's files in
<out>/<sequence>/<configuration>/.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import statistics
import sys
import time
from pathlib import Path

from slslam.config import Config, config_from_dict
from slslam.sim import SimOptions, Simulator
from slslam.tracking import run_sequence

from common import RESULTS_DIR, parse_overrides, with_xfeat_preset, write_results

SEQUENCES = {
    "loop_l100": {"preset": "loop", "light": 1.0},
    "loop_l015_dust": {"preset": "loop", "light": 0.15, "dust": True},
    "junction_hard": {
        "preset": "junction",
        "light": 0.15,
        "dust": True,
        "flicker": True,
        "blackout": True,
    },
    "junction_spin": {"preset": "junction", "light": 0.5, "spin_at_s": 10.0},
}
CONFIGS = {  # name: (label, point front end, low-texture fallback, lines)
    "orb_lines": ("ORB + lines", "orb", True, True),
    "orb_lines_plain": ("ORB + lines, plain ORB detection", "orb", False, True),
    "orb": ("ORB points", "orb", True, False),
    "xfeat_lines": ("XFeat + lines (configs/xfeat.yaml)", "xfeat", True, True),
}
ESTIMATED = ("OK", "RELOCALISED", "NEW_MAP")


def simulate(name: str, frames: int, data_dir: Path) -> Path | None:
    out = data_dir / name
    if (out / "mav0").is_dir():
        return out
    options = SEQUENCES[name]
    known = {f.name for f in dataclasses.fields(SimOptions)}
    if not set(options) <= known:
        print(f"skipping {name}: this simulator has no {sorted(set(options) - known)}")
        return None
    print(f"simulating {name} ({frames} frames) into {out}", flush=True)
    Simulator(SimOptions(frames=frames, lidar=False, **options)).write(out, progress=False)
    return out


def config_for(name: str, overrides: dict | None = None) -> Config:
    _, frontend, fallback, lines = CONFIGS[name]
    if frontend == "xfeat":
        overrides = with_xfeat_preset(overrides)
    base = config_from_dict(overrides) if overrides else Config()
    features = dataclasses.replace(
        base.features, point_frontend=frontend, low_texture_fallback=fallback
    )
    tracking = dataclasses.replace(base.tracking, use_lines=lines)
    return dataclasses.replace(base, features=features, tracking=tracking)


def summarise(out: Path, metrics: dict) -> dict:
    with (out / "frames.csv").open() as f:
        rows = list(csv.DictReader(f))
    keypoints = [int(r["keypoints"]) for r in rows]
    # The hard stretch: the tenth of the frames with the fewest weighted inliers (after start).
    ranked = sorted(rows[1:], key=lambda r: float(r["weighted_inliers"]))
    hard = ranked[: max(1, len(ranked) // 10)]
    ape = metrics.get("ape", {})
    return {
        "frames": metrics["frames"],
        "posed_after_init": metrics.get("posed_ratio_after_init"),
        "relocalisations": metrics.get("relocalisations"),
        "inertial_frames": metrics.get("inertial_frames"),
        "new_maps_after_loss": metrics.get("new_maps_after_loss"),
        "lost_frames": metrics.get("lost_frames"),
        "lost_s": metrics.get("lost_s"),
        "maps": metrics.get("maps"),
        "ate_rmse_m": ape.get("rmse"),
        "ate_percent_of_path": metrics.get("ape_rmse_percent_of_path"),
        "path_m": metrics.get("path_length_m"),
        "keypoints_median": statistics.median(keypoints) if keypoints else 0,
        "keypoints_hard_stretch": statistics.median(int(r["keypoints"]) for r in hard),
        "inliers_hard_stretch": statistics.median(float(r["weighted_inliers"]) for r in hard),
        "keyframes": metrics.get("keyframes"),
        "median_total_ms": metrics["median_ms"]["total"],
        "evaluation_error": metrics.get("evaluation_error"),
    }


def table(results: dict) -> str:
    head = (
        "| sequence | configuration | frames | posed after init | relocalisations | new maps "
        "| IMU-bridged frames | lost frames | maps | ATE RMSE [m] | ATE % of path "
        "| keypoints (hard stretch) | keyframes | ms/frame |"
    )
    lines = [head, "|" + "---|" * 14]
    for seq, runs in results.items():
        for cfg, r in runs.items():
            ate = "-" if r["ate_rmse_m"] is None else f"{r['ate_rmse_m']:.4f}"
            pct = "-" if r["ate_percent_of_path"] is None else f"{r['ate_percent_of_path']:.2f}"
            lines.append(
                f"| {seq} | {CONFIGS[cfg][0]} | {r['frames']} | {r['posed_after_init']:.3f} "
                f"| {r['relocalisations']} | {r['new_maps_after_loss']} "
                f"| {r['inertial_frames']} | {r['lost_frames']} "
                f"| {r['maps']} | {ate} | {pct} | {r['keypoints_median']:.0f} "
                f"({r['keypoints_hard_stretch']:.0f}) | {r['keyframes']} "
                f"| {r['median_total_ms']:.1f} |"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sequences", nargs="+", default=list(SEQUENCES), choices=SEQUENCES)
    parser.add_argument("--configs", default="orb_lines,orb_lines_plain")
    parser.add_argument("--frames", type=int, default=600)
    parser.add_argument("--data-dir", type=Path, default=RESULTS_DIR / "tracking_recovery_data")
    parser.add_argument("--out", type=Path, default=RESULTS_DIR / "tracking_recovery")
    parser.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE", help="config override"
    )
    args = parser.parse_args(argv)
    overrides = parse_overrides(args.set)
    configs = [c for c in args.configs.split(",") if c]
    unknown = sorted(set(configs) - set(CONFIGS))
    if unknown:
        parser.error(f"unknown configuration {unknown[0]!r} (known: {sorted(CONFIGS)})")
    if args.frames < 2:
        parser.error("--frames must be >= 2")
    results: dict = {}
    for seq in args.sequences:
        data = simulate(seq, args.frames, args.data_dir)
        if data is None:
            continue
        for cfg in configs:
            out = args.out / seq / cfg
            start = time.perf_counter()
            summary = run_sequence(data, out, config=config_for(cfg, overrides), progress=False)
            r = summarise(out, summary.metrics)
            print(
                f"{seq:15s} {cfg:16s} posed {r['posed_after_init']:.3f} ATE "
                f"{r['ate_rmse_m']} m ({r['ate_percent_of_path']} %) maps {r['maps']} "
                f"[{time.perf_counter() - start:.0f} s]",
                flush=True,
            )
            results.setdefault(seq, {})[cfg] = r
    text = table(results)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "tracking_recovery.md").write_text(text + "\n")
    path = write_results(
        "tracking_recovery",
        {"frames": args.frames, "overrides": overrides, "results": results},
        args.out / "tracking_recovery.json",
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
