"""Holding on and coming back: the tracker on simulated hard cases (issue 13's measurements).

    python benchmarks/tracking_recovery.py [--sequences loop_l100 loop_l015_dust junction_hard
        junction_spin] [--configs orb_lines,orb_lines_plain,orb] [--frames 600]
        [--seeds 0 1 2] [--data-dir DIR] [--out DIR] [--set tracking.KEY=VALUE ...]

Sequences (seed 0 unless --seeds, no LiDAR, simulated once into --data-dir; seed N > 0 into
--data-dir/seedN): the loop at light 1.0
(loop_l100) and at 0.15 with dust (loop_l015_dust); the junction at 0.15 with dust, exposure
flicker and a 1 s headlamp blackout (junction_hard); the junction at light 0.5 with a 360 degree
turn on the spot at t = 10 s (junction_spin, when the simulator offers ``spin_at_s``). Asked
for by name only: the junction at light 0.5 with a 1 s blackout in the middle
(junction_blackout; ``--frames 160 --set tracking.imu.enabled=false`` is the camera-only pytest's
run, ``--seeds 0 1 ... 11`` how often it comes back into the one map and where).
Configurations, each with its front end's preset (python/slslam/presets/): ORB + lines
(orb_lines); XFeat + lines (xfeat_lines); ORB + lines with the low-texture fallback off,
i.e. plain OpenCV ORB detection as before it (orb_lines_plain); ORB points only (orb).

Per run: frames with an estimated pose after the first initialisation (OK, RELOCALISED, NEW_MAP,
INERTIAL), relocalisations, new maps after a loss, frames the IMU carried (the simulator writes
imu0/, used by default; ``--set tracking.imu.enabled=false`` for camera only), frames and
seconds without an estimate, maps, ATE RMSE over every estimated frame (evo, SE3 alignment of
the whole run) in metres and as a share of the path driven, median keypoints per frame (whole
run and over the frames whose inliers were lowest, the hard stretch), keyframes and median time
per frame. Writes tracking_recovery.md and .json in --out and each run's files in
<out>/<sequence>/<configuration>/ (<out>/seedN/<sequence>/<configuration>/ for seed N > 0).

One seed's long dark runs are chaotic: the hard junction's ATE moved from 0.089 to 0.204 m
between seeds 0-2 with the same settings (benchmarks/log/realtime.md, 2026-11-27 d), so a change of
20-50 % on one seed says little. ``--seeds 0 1 2`` runs every sequence with each simulator seed
(other noise, dust and jitter on the same roadway) and adds a table of the mean ATE over the seeds
with its smallest and largest.
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

from common import RESULTS_DIR, parse_overrides, write_results

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
    # the camera-only blackout of tests/python/test_tracking.py (with --frames 160 and
    # --set tracking.imu.enabled=false): how the tracker comes back after 1 s of darkness
    "junction_blackout": {"preset": "junction", "light": 0.5, "blackout": True},
    # issue 62's hard cases (benchmarks/hard_cases.py runs them, each with its own length):
    # 16 m of smooth shotcrete (no arches, bolts, pipe, cables, nearly uniform walls, roof and
    # floor) on the loop's first straight, 5-21 m along the path, at light 1.0 ...
    "shotcrete_l100": {
        "preset": "loop",
        "light": 1.0,
        "shotcrete_start_m": 5.0,
        "shotcrete_length_m": 16.0,
    },
    # ... and at light 0.15 with dust
    "shotcrete_l015_dust": {
        "preset": "loop",
        "light": 0.15,
        "dust": True,
        "shotcrete_start_m": 5.0,
        "shotcrete_length_m": 16.0,
    },
    # the dead-end branch lined with shotcrete from 11 m along the path to its face (25 m of
    # it), light 0.5 with flicker; the robot comes to rest 18 m along the path (7 m into the
    # lining, at t = 24.5 s), stands still 3 s, turns 360 degrees on the spot in 6 s facing the
    # smooth walls, and drives on towards the face
    "shotcrete_branch": {
        "preset": "dead_end",
        "light": 0.5,
        "flicker": True,
        "shotcrete_start_m": 11.0,
        "shotcrete_length_m": 26.0,
        "spin_at_s": 24.5,
        "stop_duration_s": 3.0,
        "spin_deg": 360.0,
        "spin_duration_s": 6.0,
    },
    # a 4 s blackout (twice the 2 s the earlier IMU bridge carried) from t = 8 s on the junction
    # at light 0.5
    "blackout_long": {
        "preset": "junction",
        "light": 0.5,
        "blackout": True,
        "blackout_s": 4.0,
        "blackout_at_s": 8.0,
    },
}
# The three shotcrete cases again with the lining's relief (sim SimOptions.shotcrete_relief_m 6 mm:
# lumps of 2.4-10 cm, height RMS about 1.2 mm, slope RMS 0.059 rad) that the headlamp shades as a
# faint texture changing with the light's direction; without it the lining is flat (the camera
# sees nothing there but a 3 % grain: the limit of dead reckoning). Name: flat case it varies.
RELIEF_CASES = {
    "shotcrete_relief_l100": "shotcrete_l100",
    "shotcrete_relief_l015_dust": "shotcrete_l015_dust",
    "shotcrete_relief_branch": "shotcrete_branch",
}
SEQUENCES.update(
    {name: {**SEQUENCES[flat], "shotcrete_relief_m": 0.006} for name, flat in RELIEF_CASES.items()}
)
DEFAULT_SEQUENCES = ["loop_l100", "loop_l015_dust", "junction_hard", "junction_spin"]
CONFIGS = {  # name: (label, point front end, low-texture fallback, lines)
    "orb_lines": ("ORB + lines", "orb", True, True),
    "orb_lines_plain": ("ORB + lines, plain ORB detection", "orb", False, True),
    "orb": ("ORB points", "orb", True, False),
    "xfeat_lines": ("XFeat + lines", "xfeat", True, True),
}
ESTIMATED = ("OK", "RELOCALISED", "NEW_MAP")


def seed_dir(root: Path, seed: int) -> Path:
    """Where a seed's data and runs go: the root itself for seed 0 (as before seeds existed)."""
    return root if seed == 0 else root / f"seed{seed}"


def simulate(name: str, frames: int, data_dir: Path, seed: int = 0) -> Path | None:
    out = seed_dir(data_dir, seed) / name
    if (out / "mav0").is_dir():
        return out
    options = dict(SEQUENCES[name], seed=seed)
    known = {f.name for f in dataclasses.fields(SimOptions)}
    if not set(options) <= known:
        print(f"skipping {name}: this simulator has no {sorted(set(options) - known)}")
        return None
    print(f"simulating {name} ({frames} frames, seed {seed}) into {out}", flush=True)
    Simulator(SimOptions(frames=frames, lidar=False, **options)).write(out, progress=False)
    return out


def config_for(name: str, overrides: dict | None = None) -> Config:
    _, frontend, fallback, lines = CONFIGS[name]
    # the front end's preset (XFeat's: python/slslam/presets/xfeat.yaml) under the overrides
    base = config_from_dict(overrides, point_frontend=frontend)
    features = dataclasses.replace(base.features, low_texture_fallback=fallback)
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
        "| IMU-carried frames | lost frames | maps | ATE RMSE [m] | ATE % of path "
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


def seed_table(per_seed: dict, seeds: list[int]) -> str:
    """Mean ATE over the seeds, with the smallest and the largest, per sequence and config."""
    head = "| sequence | configuration | " + " | ".join(f"seed {s}" for s in seeds)
    head += " | mean ATE [m] | min-max [m] | maps (max) |"
    lines = [head, "|" + "---|" * (len(seeds) + 5)]
    for seq, runs in per_seed.items():
        for cfg, by_seed in runs.items():
            ates = [by_seed[s]["ate_rmse_m"] for s in seeds if s in by_seed]
            cells = [
                "-"
                if by_seed.get(s, {}).get("ate_rmse_m") is None
                else f"{by_seed[s]['ate_rmse_m']:.4f}"
                for s in seeds
            ]
            known = [a for a in ates if a is not None]
            mean = f"{statistics.fmean(known):.4f}" if known else "-"
            spread = f"{min(known):.4f}-{max(known):.4f}" if known else "-"
            maps = max((r["maps"] or 0) for r in by_seed.values())
            lines.append(
                f"| {seq} | {CONFIGS[cfg][0]} | "
                + " | ".join(cells)
                + f" | {mean} | {spread} | {maps} |"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sequences", nargs="+", default=DEFAULT_SEQUENCES, choices=SEQUENCES)
    parser.add_argument("--configs", default="orb_lines,orb_lines_plain")
    parser.add_argument("--frames", type=int, default=600)
    parser.add_argument(
        "--seeds",
        type=int,
        nargs="+",
        default=[0],
        help="simulator seeds; each sequence is run once per seed (default: 0)",
    )
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
    if any(s < 0 for s in args.seeds) or len(set(args.seeds)) != len(args.seeds):
        parser.error("--seeds must be distinct non-negative integers")
    seeds = list(args.seeds)
    results: dict = {}  # "<sequence>" (seed 0) or "<sequence> (seed N)" -> config -> summary
    per_seed: dict = {}  # sequence -> config -> seed -> summary
    for seed in seeds:
        for seq in args.sequences:
            data = simulate(seq, args.frames, args.data_dir, seed)
            if data is None:
                continue
            key = seq if seed == 0 else f"{seq} (seed {seed})"
            for cfg in configs:
                out = seed_dir(args.out, seed) / seq / cfg
                start = time.perf_counter()
                config = config_for(cfg, overrides)
                summary = run_sequence(data, out, config=config, progress=False)
                r = summarise(out, summary.metrics)
                print(
                    f"{key:15s} {cfg:16s} posed {r['posed_after_init']:.3f} ATE "
                    f"{r['ate_rmse_m']} m ({r['ate_percent_of_path']} %) maps {r['maps']} "
                    f"[{time.perf_counter() - start:.0f} s]",
                    flush=True,
                )
                results.setdefault(key, {})[cfg] = r
                per_seed.setdefault(seq, {}).setdefault(cfg, {})[seed] = r
    text = table(results)
    if len(seeds) > 1:
        text += "\n\n" + seed_table(per_seed, seeds)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "tracking_recovery.md").write_text(text + "\n")
    path = write_results(
        "tracking_recovery",
        {"frames": args.frames, "seeds": seeds, "overrides": overrides, "results": results},
        args.out / "tracking_recovery.json",
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
