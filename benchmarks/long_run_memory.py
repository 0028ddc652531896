"""Long run: resident memory and map size over 10,000 simulated frames (issue 17 item 5).

    python benchmarks/long_run_memory.py [--frames 10000] [--every 100] [--light 1.0]
        [--loop-length-m 40] [--loop-radius-m 10] [--rate-hz 20] [--speed-mps 0.8]
        [--out benchmarks/results/long_run_memory]
    python benchmarks/long_run_memory.py --from-csv OUT/memory.csv   # plot and summarise

The simulated loop roadway (by default 142.75 m, 3,589 frames at 0.8 m/s and 20 Hz, 752 x 480;
``--loop-length-m/--loop-radius-m/--rate-hz/--speed-mps`` pick a smaller or faster one) is driven
lap after lap: frame k shows lap frame k mod 3,589 (rendered on the fly, one frame ahead on a
second thread; the robot stops at the end of a lap and starts again where it began), with
timestamps that keep increasing. The tracker runs with the default configuration (the point
front end it picks is reported). Every ``--every`` frames the script records the process's
resident memory (VmRSS from /proc/self/status) and the map: keyframes, points, lines, maps, and
the culling counters. Writes ``memory.csv`` (row by row, so an interrupted run keeps its
samples), ``memory.png`` and ``summary.json`` in ``--out``; ``--from-csv`` makes the last two from
the samples of a run, finished or not.

This is a benchmark, not a test: it takes about an hour on two cores.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import logging
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from slslam.config import default_config, make_point_frontend
from slslam.datasets.euroc import RectifiedStereoCamera
from slslam.progress import progress_bar
from slslam.sim import SimOptions, Simulator
from slslam.sim.sequence import preset_geometry
from slslam.sim.trajectory import RobotTrajectory
from slslam.tracking import Tracker

from common import RESULTS_DIR, machine

COLUMNS = (
    "frame",
    "seconds",
    "rss_mib",
    "keyframes",
    "points",
    "lines",
    "maps",
    "keyframes_culled",
    "points_culled",
    "lines_culled",
    "tracked_share_window",
    "loops_accepted",
    "merges",
)


def resident_mib() -> float:
    """The process's resident set size [MiB] (Linux /proc)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS in /proc/self/status (this benchmark needs Linux)")


def lap_frames(options: SimOptions) -> int:
    """Frames of one full lap of the preset's path at the options' speed and rate."""
    path = preset_geometry(
        options.preset, options.laps, options.loop_length_m, options.loop_radius_m
    )[1]
    full = RobotTrajectory(path, options=options.trajectory_options()).duration_s
    return int(full * options.rate_hz)


def camera_of(sim: Simulator) -> RectifiedStereoCamera:
    cam = sim.camera
    return RectifiedStereoCamera(
        cam.fx, cam.fx, cam.cx, cam.cy, cam.width, cam.height, cam.baseline_m, cam.T_body_cam0
    )


def plot(rows: list[dict], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    frame = [r["frame"] for r in rows]
    fig, (ax_mem, ax_map) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    ax_mem.plot(frame, [r["rss_mib"] for r in rows], color="C3")
    ax_mem.set_ylabel("resident memory [MiB]")
    ax_mem.set_title(title)
    ax_mem.grid(alpha=0.3)
    ax_map.plot(frame, [r["points"] for r in rows], label="map points")
    ax_map.plot(frame, [r["lines"] for r in rows], label="map lines")
    ax_map.plot(frame, [10 * r["keyframes"] for r in rows], label="keyframes x 10")
    ax_map.set_xlabel("frame")
    ax_map.set_ylabel("count")
    ax_map.legend()
    ax_map.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def read_rows(path: Path) -> list[dict]:
    with path.open(newline="") as handle:
        return [
            {k: (float(v) if "." in v else int(v)) for k, v in row.items()}
            for row in csv.DictReader(handle)
        ]


def summarise(rows: list[dict], out: Path, extra: dict) -> dict:
    """summary.json and memory.png from the samples; memory growth per 1,000 frames over the
    second half of the run (about 0 once memory has flattened) and per keyframe."""
    first, last = rows[0], rows[-1]
    half = [r for r in rows if r["frame"] > last["frame"] / 2]
    frames = [r["frame"] for r in half]
    slope = float(np.polyfit(frames, [r["rss_mib"] for r in half], 1)[0]) * 1e3
    kf_slope = float(np.polyfit(frames, [r["keyframes"] for r in half], 1)[0]) * 1e3
    growth = last["rss_mib"] - first["rss_mib"]
    summary = {
        "benchmark": "long_run_memory",
        "machine": machine(),
        **extra,
        "frames_run": last["frame"],
        "first": first,
        "last": last,
        "rss_growth_second_half_mib_per_1000_frames": round(slope, 2),
        "keyframes_added_second_half_per_1000_frames": round(kf_slope, 1),
        "rss_growth_per_keyframe_kib": round(
            1024 * growth / max(last["keyframes"] - first["keyframes"], 1), 1
        ),
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    frontend = extra.get("frontend", "default configuration")
    plot(rows, out / "memory.png", f"{last['frame']} frames, {frontend}, resident memory and map")
    return summary


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=10_000)
    parser.add_argument("--every", type=int, default=100, help="sample every N frames")
    parser.add_argument("--light", type=float, default=1.0)
    parser.add_argument("--loop-length-m", type=float, default=SimOptions.loop_length_m)
    parser.add_argument("--loop-radius-m", type=float, default=SimOptions.loop_radius_m)
    parser.add_argument("--rate-hz", type=float, default=SimOptions.rate_hz)
    parser.add_argument("--speed-mps", type=float, default=SimOptions.speed_mps)
    parser.add_argument("--out", type=Path, default=RESULTS_DIR / "long_run_memory")
    parser.add_argument("--from-csv", type=Path, help="only plot and summarise this memory.csv")
    args = parser.parse_args(argv)
    if args.from_csv is not None:
        summary = summarise(read_rows(args.from_csv), args.from_csv.parent, {"from_csv": True})
        print(json.dumps(summary, indent=2))
        return 0
    if args.frames < 1 or args.every < 1:
        parser.error("--frames and --every must be >= 1")
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    args.out.mkdir(parents=True, exist_ok=True)

    base = SimOptions(
        preset="loop",
        light=args.light,
        lidar=False,
        loop_length_m=args.loop_length_m,
        loop_radius_m=args.loop_radius_m,
        rate_hz=args.rate_hz,
        speed_mps=args.speed_mps,
    )
    lap = lap_frames(base)
    sim = Simulator(dataclasses.replace(base, frames=lap))
    config = default_config("orb")
    frontend = make_point_frontend(config.features)
    print(
        f"{args.frames} frames, loop lap {lap} frames, front end {type(frontend).__name__}",
        flush=True,
    )

    rows: list[dict] = []
    tracked_window = 0
    start = time.perf_counter()
    csv_path = args.out / "memory.csv"
    with (
        Tracker(camera_of(sim), config, frontend=frontend) as tracker,
        ThreadPoolExecutor(max_workers=1) as pool,
        csv_path.open("w", newline="") as handle,
    ):
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        writer.writeheader()
        pending = pool.submit(sim.render_stereo, 0)
        for k in progress_bar(range(args.frames), desc="long run", unit="frame"):
            left, right, _ = pending.result()
            if k + 1 < args.frames:
                pending = pool.submit(sim.render_stereo, (k + 1) % lap)
            result = tracker.track(left, right, k / base.rate_hz)
            tracked_window += result.tracked
            if (k + 1) % args.every == 0 or k + 1 == args.frames:
                m = tracker.map()
                row = {
                    "frame": k + 1,
                    "seconds": round(time.perf_counter() - start, 1),
                    "rss_mib": round(resident_mib(), 1),
                    "keyframes": m.keyframes,
                    "points": len(m.points),
                    "lines": len(m.lines),
                    "maps": m.maps,
                    "keyframes_culled": m.stats.keyframes_culled,
                    "points_culled": m.stats.points_culled,
                    "lines_culled": m.stats.lines_culled,
                    "tracked_share_window": round(tracked_window / args.every, 3),
                    "loops_accepted": m.stats.loops_accepted,
                    "merges": m.stats.merges,
                }
                tracked_window = 0
                rows.append(row)
                writer.writerow(row)
                handle.flush()
        states = [r.state for r in tracker.results]

    extra = {
        "frames": args.frames,
        "lap_frames": lap,
        "light": args.light,
        "loop_length_m": args.loop_length_m,
        "loop_radius_m": args.loop_radius_m,
        "rate_hz": args.rate_hz,
        "speed_mps": args.speed_mps,
        "frontend": type(frontend).__name__,
        "resolution": [sim.camera.width, sim.camera.height],
        "seconds": round(time.perf_counter() - start, 1),
        "states": {s: states.count(s) for s in sorted(set(states))},
    }
    summary = summarise(rows, args.out, extra)
    print(json.dumps(summary, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
