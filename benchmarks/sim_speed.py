"""Simulator throughput: stereo frames per second written at 752x480, and where the time goes.

    python benchmarks/sim_speed.py [--frames 60] [--out FILE]

Runs, in one process and one after the other: the full writer (images, LiDAR, IMU, ground truth)
for the default loop at light 1.0 and at 0.15 with dust and moving objects, then times the stages
of one frame (ray casting both cameras, shading one image, writing one PNG).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from slslam import _core
from slslam.sim import SimOptions, Simulator

from common import time_calls, write_results


def throughput(options: SimOptions) -> dict[str, float]:
    sim = Simulator(options)
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        manifest = sim.write(Path(tmp) / "seq", progress=False)
        elapsed = time.perf_counter() - start
    return {
        "frames": manifest["frames_written"],
        "seconds": elapsed,
        "frames_per_second": manifest["frames_written"] / elapsed,
    }


def stages(options: SimOptions) -> dict[str, dict[str, float]]:
    sim = Simulator(options)
    cam = sim.camera
    T_body = sim.trajectory.pose(np.array([1.0]))[0]
    poses = [T_body @ cam.T_body_cam0, T_body @ cam.T_body_cam1]
    hits = sim.cast_cameras(poses, 1.0)[0]
    lamp = sim._headlamp(T_body)
    image = sim.render_stereo(20)[0]
    with tempfile.TemporaryDirectory() as tmp:
        png = str(Path(tmp) / "x.png")
        return {
            "raycast_both_cameras": time_calls(lambda: sim.cast_cameras(poses, 1.0), 10),
            "shade_one_image": time_calls(lambda: sim.shade(hits, poses[0], lamp, 1.0, 0), 10),
            "write_one_png": time_calls(lambda: _core.write_image(png, image), 10),
            "lidar_scan": time_calls(
                lambda: sim.lidar.scan(
                    sim.scene, T_body @ sim.lidar.T_body_lidar, np.random.default_rng(0)
                ),
                10,
            ),
            "render_stereo_frame": time_calls(lambda: sim.render_stereo(20), 10),
        }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=60)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    runs = {
        "loop_light1.0": SimOptions(preset="loop", frames=args.frames, light=1.0),
        "loop_light0.15_dust_movers": SimOptions(
            preset="loop", frames=args.frames, light=0.15, dust=True, movers=True
        ),
    }
    results = {
        "image_size": [752, 480],
        "throughput": {name: throughput(opts) for name, opts in runs.items()},
        "stages_ms": stages(SimOptions(preset="loop", frames=args.frames)),
    }
    for name, r in results["throughput"].items():
        print(f"{name:30s} {r['frames_per_second']:6.2f} stereo frames/s ({r['frames']} frames)")
    for name, r in results["stages_ms"].items():
        print(f"{name:30s} median {r['median_ms']:7.1f} ms")
    print(f"wrote {write_results('sim_speed', results, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
