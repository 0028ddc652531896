"""Loop closing and map merging on simulated mine roadways, with and without loop closing.

    python benchmarks/loop_closing.py [--out benchmarks/results/loop_closing]
        [--sequences loop_bright,loop_dark,corridor] [--frames N]

Sequences (rendered once into --data, default /tmp/slslam_loop_closing), each with its own
default frame count (--frames overrides it for all):
  loop_bright  a small yard loop (10 m straights, 4 m half circles: 45 m a lap) driven 2 laps
               at 1 m/s, 10 Hz (900 frames), light 1.0: the second lap revisits the first
  loop_dark    the same at light 0.15 with dust
  corridor     the straight 80 m roadway at light 1.0 (700 frames): arches and mesh repeat, no
               place is visited twice, so every accepted loop there is false
  full_bright  the simulator's default yard loop (40 m straights, 10 m half circles: 143 m a
               lap) driven 2 laps at 1 m/s, 10 Hz (2,840 frames), light 1.0
  full_dark    the same at light 0.15 with dust

Per sequence, loop closing on and off (tracking.loop_closing.enabled / merge_maps): frames
posed, maps at the end, ATE RMSE of the final trajectory (frames through their corrected
keyframes) and of the online one, loops detected / accepted / false (an accepted loop whose two
keyframes are more than 2 m apart in the ground truth), merges, loop-closing and global-BA time.
Then the map saved by the loop_bright run is reloaded and localises the whole sequence again in
localisation-only mode. Writes loop_closing.json and loop_closing.md into --out.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time
from pathlib import Path

import numpy as np

from slslam.config import Config, config_from_dict
from slslam.sim import SimOptions, Simulator
from slslam.tracking import run_sequence

from common import parse_overrides

SEQUENCES = {
    "loop_bright": dict(
        preset="loop", rate_hz=10.0, speed_mps=1.0, laps=2, loop_length_m=10.0, loop_radius_m=4.0
    ),
    "loop_dark": dict(
        preset="loop",
        rate_hz=10.0,
        speed_mps=1.0,
        laps=2,
        loop_length_m=10.0,
        loop_radius_m=4.0,
        light=0.15,
        dust=True,
    ),
    "corridor": dict(preset="straight", rate_hz=10.0, speed_mps=1.0),
    "full_bright": dict(preset="loop", rate_hz=10.0, speed_mps=1.0, laps=2),
    "full_dark": dict(preset="loop", rate_hz=10.0, speed_mps=1.0, laps=2, light=0.15, dust=True),
}
FRAMES = {"loop_bright": 900, "loop_dark": 900, "corridor": 700}
FRAMES.update(full_bright=2840, full_dark=2840)
FALSE_LOOP_M = 2.0


def simulate(name: str, frames: int, data: Path) -> Path:
    out = data / f"{name}_{frames}"
    manifest = out / "manifest.json"
    complete = manifest.exists() and json.loads(manifest.read_text()).get("status") == "complete"
    if not complete:  # absent, or a render that was interrupted
        print(f"simulating {name} ({frames} frames) into {out}", flush=True)
        Simulator(SimOptions(frames=frames, lidar=False, **SEQUENCES[name])).write(
            out, progress=False
        )
    return out


def with_loops(enabled: bool, threaded: bool = False, overrides: dict | None = None) -> Config:
    # ORB + lines, as every result of this benchmark in benchmarks/log/loop_closing.md
    config = config_from_dict(overrides, point_frontend="orb")
    loop = dataclasses.replace(config.tracking.loop_closing, enabled=enabled, merge_maps=enabled)
    tracking = dataclasses.replace(config.tracking, loop_closing=loop)
    if threaded:  # local mapping and loop closing on their own thread, global BA in the background
        tracking = dataclasses.replace(tracking, sequential=False)
    return dataclasses.replace(config, tracking=tracking)


def summarise(metrics: dict, sequence: Path, seconds: float) -> dict:
    gt = np.loadtxt(sequence / "groundtruth_cam0.tum")[:, 1:4]
    events = metrics.get("loop_events", [])
    false = [
        e
        for e in events
        if np.linalg.norm(gt[e["frame_index"]] - gt[e["candidate_frame_index"]]) > FALSE_LOOP_M
    ]
    return {
        "frames": metrics["frames"],
        "posed_ratio": metrics.get("posed_ratio_after_init"),
        "maps": metrics.get("maps"),
        "ate_rmse_m": metrics.get("ape", {}).get("rmse"),
        "ate_online_rmse_m": metrics.get("ape_online", {}).get("rmse"),
        "loops": metrics.get("loops"),
        "false_loops": len(false),
        "merges": metrics.get("merges"),
        "loop_closing_ms": metrics.get("loop_closing_ms"),
        "global_ba_ms": metrics.get("global_ba_ms"),
        "global_ba_runs": metrics.get("global_ba_runs"),
        "global_ba_lock_ms": metrics.get("global_ba_lock_ms"),
        "global_ba_cancelled": metrics.get("global_ba_cancelled"),
        "welding_ba_runs": metrics.get("welding_ba_runs"),
        "welding_ba_ms": metrics.get("welding_ba_ms"),
        "keyframes": metrics.get("keyframes"),
        "seconds": round(seconds, 1),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/loop_closing"))
    parser.add_argument("--data", type=Path, default=Path("/tmp/slslam_loop_closing"))
    parser.add_argument("--sequences", default="loop_bright,loop_dark,corridor")
    parser.add_argument(
        "--frames", type=int, default=None, help="frames per sequence (default: per sequence)"
    )
    parser.add_argument(
        "--threaded",
        action="store_true",
        help="tracking.sequential: false (local mapping and loop closing on their own thread, "
        "global BA in the background; not bit-for-bit reproducible)",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="config override for every run, e.g. tracking.loop_closing.welding_keyframes=0",
    )
    parser.add_argument(
        "--loops-only", action="store_true", help="skip the runs with loop closing off"
    )
    args = parser.parse_args()
    overrides = parse_overrides(args.set)
    args.out.mkdir(parents=True, exist_ok=True)
    results: dict = {"load_average": os.getloadavg(), "runs": {}}
    for name in args.sequences.split(","):
        sequence = simulate(name, args.frames or FRAMES[name], args.data)
        for enabled in (True,) if args.loops_only else (True, False):
            label = f"{name}/{'loops' if enabled else 'no_loops'}"
            out = args.out / name / ("loops" if enabled else "no_loops")
            save = out / "atlas.slmap" if enabled and name.endswith("_bright") else None
            start = time.perf_counter()
            summary = run_sequence(
                sequence,
                out,
                with_loops(enabled, args.threaded, overrides),
                progress=False,
                save_map=save,
            )
            results["runs"][label] = summarise(
                summary.metrics, sequence, time.perf_counter() - start
            )
            print(label, json.dumps(results["runs"][label]), flush=True)
            if save is not None:
                start = time.perf_counter()
                again = run_sequence(
                    sequence,
                    args.out / name / "localise_only",
                    with_loops(True, args.threaded, overrides),  # the front end that made the map
                    progress=False,
                    load_map=save,
                    localise_only=True,
                )
                results["runs"][f"{name}/localise_only"] = summarise(
                    again.metrics, sequence, time.perf_counter() - start
                )
                print(f"{name}/localise_only", json.dumps(results["runs"][f"{name}/localise_only"]))
    (args.out / "loop_closing.json").write_text(json.dumps(results, indent=2))
    lines = [
        "| run | frames | posed | maps | ATE final [m] | ATE online [m] | loops det/acc/false "
        "| merges | loop ms | global BA ms (runs) | of which map locked ms "
        "| welding BA ms (runs) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for label, r in results["runs"].items():
        loops = r["loops"] or {}
        ate = r["ate_rmse_m"] or float("nan")
        online = r["ate_online_rmse_m"] or float("nan")
        lines.append(
            f"| {label} | {r['frames']} | {r['posed_ratio']:.3f} | {r['maps']} "
            f"| {ate:.4f} | {online:.4f} "
            f"| {loops.get('detected', 0)}/{loops.get('accepted', 0)}/{r['false_loops']} "
            f"| {r['merges']} | {r['loop_closing_ms'] or 0:.0f} "
            f"| {r['global_ba_ms'] or 0:.0f} ({r['global_ba_runs'] or 0}) "
            f"| {r['global_ba_lock_ms'] or 0:.0f} "
            f"| {r['welding_ba_ms'] or 0:.0f} ({r['welding_ba_runs'] or 0}) |"
        )
    (args.out / "loop_closing.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
