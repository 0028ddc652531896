"""Issue 62's hard simulated cases: smooth shotcrete, a stop and a turn on the spot in it, and a
headlamp blackout of 4 s; the tracker on each, camera only by default.

    python benchmarks/hard_cases.py [--cases shotcrete_l100 shotcrete_l015_dust
        shotcrete_branch blackout_long shotcrete_relief_l100 ...] [--configs orb_lines,xfeat_lines]
        [--imu]
        [--frames-scale 1.0] [--data-dir DIR] [--out DIR] [--set tracking.KEY=VALUE ...]

The cases are defined in tracking_recovery.py's SEQUENCES (so ``tracking_recovery.py
--sequences shotcrete_l100`` runs one too, at its --frames): 16 m of smooth shotcrete on the
loop's first straight at light 1.0 (shotcrete_l100) and at 0.15 with dust (shotcrete_l015_dust);
the dead-end branch lined with shotcrete up to its face, light 0.5 with flicker, a 3 s stop and
a 360 degree turn on the spot 7 m into the lining (shotcrete_branch); a 4 s blackout on the
junction at light 0.5 (blackout_long); and the three shotcrete cases with the lining's relief
(shotcrete_relief_l100, shotcrete_relief_l015_dust, shotcrete_relief_branch: SimOptions.
shotcrete_relief_m 6 mm, a faint texture the headlamp shades; flat, the lining shows nothing).
Each is simulated (seed 0, no LiDAR) with the frames it needs to get through its hard part and a
little beyond, once, into --data-dir.

Configurations as in tracking_recovery.py: ORB + lines (orb_lines, `slslam run --orb`), XFeat +
lines (xfeat_lines, `slslam run --xfeat`), ... Camera only unless --imu (then the IMU is coupled
in, as `slslam run` does by default on the simulator's imu0/).

Per run, besides tracking_recovery.py's table: the hard part's frames (the robot inside the
shotcrete stretch, or the lights out), the share of them with a camera pose (OK, RELOCALISED,
NEW_MAP; INERTIAL counted apart), the median keypoints inside and outside the hard part, maps
and ATE RMSE (evo, SE3 alignment of the whole run). Writes hard_cases.md and .json in --out.
"""

from __future__ import annotations

import argparse
import csv
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from slslam.sim import SimOptions, Simulator
from slslam.sim.roadway import Stations
from slslam.sim.sequence import preset_geometry
from slslam.tracking import run_sequence
from tracking_recovery import (
    CONFIGS,
    ESTIMATED,
    RELIEF_CASES,
    SEQUENCES,
    config_for,
    simulate,
    summarise,
    table,
)

from common import RESULTS_DIR, parse_overrides, write_results

#: Frames each case is simulated and run for (20 Hz): through the hard part and a little beyond.
CASE_FRAMES = {
    "shotcrete_l100": 600,  # the stretch is driven from t = 7.25 s to 27.25 s
    "shotcrete_l015_dust": 600,
    "shotcrete_branch": 760,  # in the lining from t = 14.75 s; stop 24.5-27.5 s, turn -33.5 s
    "blackout_long": 300,  # dark from t = 8 s to 12 s
}
# the shotcrete cases with the lining's relief, as long as the flat ones
CASE_FRAMES.update({name: CASE_FRAMES[flat] for name, flat in RELIEF_CASES.items()})
CASES = list(CASE_FRAMES)


def hard_frames(name: str, frames: int) -> np.ndarray:
    """Frame indices of the case's hard part: the robot's body inside the shotcrete stretch
    (its nearest path point's arc length in the stretch), or the lights out."""
    options = SimOptions(frames=frames, lidar=False, cameras=False, **SEQUENCES[name])
    sim = Simulator(options)
    index = np.arange(frames)
    hard = np.zeros(frames, dtype=bool)
    if options.blackout:
        hard |= np.array([sim.light_level(i) == 0.0 for i in index])
    if options.shotcrete_length_m > 0:
        _, path = preset_geometry(options.preset, 1, options.loop_length_m, options.loop_radius_m)
        st = Stations.from_centreline(path)
        body = sim.trajectory.position(index / options.rate_hz)
        s = st.s[cKDTree(st.position[:, :2]).query(body[:, :2])[1]]
        start = options.shotcrete_start_m
        hard |= (s >= start) & (s <= start + options.shotcrete_length_m)
    return index[hard]


def hard_part(out: Path, hard: np.ndarray) -> dict:
    """Posed share and keypoints inside the hard part of a run (frames.csv of run_sequence)."""
    with (out / "frames.csv").open() as f:
        rows = list(csv.DictReader(f))
    inside = set(int(i) for i in hard)
    rows_in = [r for r in rows if int(r["index"]) in inside]
    rows_out = [r for r in rows if int(r["index"]) not in inside]
    posed = sum(r["state"] in ESTIMATED for r in rows_in)
    inertial = sum(r["state"] == "INERTIAL" for r in rows_in)

    def median_keypoints(rs: list[dict]) -> float | None:
        return statistics.median(int(r["keypoints"]) for r in rs) if rs else None

    return {
        "hard_frames": len(rows_in),
        "hard_first_last": [int(hard[0]), int(hard[-1])] if len(hard) else None,
        "hard_posed": posed,
        "hard_posed_share": posed / len(rows_in) if rows_in else None,
        "hard_inertial": inertial,
        "keypoints_inside": median_keypoints(rows_in),
        "keypoints_outside": median_keypoints(rows_out),
    }


def hard_table(results: dict) -> str:
    head = (
        "| case | configuration | hard frames (first-last) | camera-posed in hard part "
        "| IMU-carried in it | keypoints inside / outside | maps | ATE RMSE [m] |"
    )
    lines = [head, "|" + "---|" * 8]
    for case, runs in results.items():
        for cfg, r in runs.items():
            first_last = r["hard_first_last"] or ["-", "-"]
            share = "-" if r["hard_posed_share"] is None else f"{r['hard_posed_share']:.3f}"
            ate = "-" if r["ate_rmse_m"] is None else f"{r['ate_rmse_m']:.3f}"
            lines.append(
                f"| {case} | {CONFIGS[cfg][0]} | {r['hard_frames']} ({first_last[0]}-"
                f"{first_last[1]}) | {r['hard_posed']} ({share}) | {r['hard_inertial']} "
                f"| {r['keypoints_inside']} / {r['keypoints_outside']} | {r['maps']} | {ate} |"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", nargs="+", default=CASES, choices=CASES)
    parser.add_argument("--configs", default="orb_lines,xfeat_lines")
    parser.add_argument("--imu", action="store_true", help="use the IMU (default: camera only)")
    parser.add_argument(
        "--frames-scale",
        type=float,
        default=1.0,
        help="run this share of each case's frames (a quick look; the hard part may be cut)",
    )
    parser.add_argument("--data-dir", type=Path, default=RESULTS_DIR / "hard_cases_data")
    parser.add_argument("--out", type=Path, default=RESULTS_DIR / "hard_cases")
    parser.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE", help="config override"
    )
    args = parser.parse_args(argv)
    if not 0.0 < args.frames_scale <= 1.0:
        parser.error("--frames-scale must be in (0, 1]")
    items = list(args.set) + ([] if args.imu else ["tracking.imu.enabled=false"])
    overrides = parse_overrides(items)
    configs = [c for c in args.configs.split(",") if c]
    unknown = sorted(set(configs) - set(CONFIGS))
    if unknown:
        parser.error(f"unknown configuration {unknown[0]!r} (known: {sorted(CONFIGS)})")
    results: dict = {}
    for case in args.cases:
        frames = max(2, round(CASE_FRAMES[case] * args.frames_scale))
        data = simulate(case, frames, args.data_dir / f"{frames}")
        if data is None:
            continue
        hard = hard_frames(case, frames)
        for cfg in configs:
            out = args.out / case / cfg
            start = time.perf_counter()
            summary = run_sequence(data, out, config=config_for(cfg, overrides), progress=False)
            r = {**summarise(out, summary.metrics), **hard_part(out, hard)}
            print(
                f"{case:20s} {cfg:12s} hard part posed {r['hard_posed']}/{r['hard_frames']} "
                f"maps {r['maps']} ATE {r['ate_rmse_m']} m [{time.perf_counter() - start:.0f} s]",
                flush=True,
            )
            results.setdefault(case, {})[cfg] = r
    text = hard_table(results) + "\n\n" + table(results)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "hard_cases.md").write_text(text + "\n")
    path = write_results(
        "hard_cases",
        {
            "frames": {c: CASE_FRAMES[c] for c in args.cases},
            "frames_scale": args.frames_scale,
            "camera_only": not args.imu,
            "overrides": overrides,
            "results": results,
        },
        args.out / "hard_cases.json",
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
