"""LiDAR-inertial SLAM against KISS-ICP on the simulator's LiDAR + IMU sequences.

    python benchmarks/lidar_slam.py [--work DIR] [--sequences loop2 straight] [--out FILE]

Sequences (rendered once into --work, LiDAR + IMU only, per-point sweep times):
``loop2``: the loop preset driven twice (7150 frames at 20 Hz, 3575 sweeps, 286 m: every place is
revisited, loop closing); ``straight``: the 80 m straight corridor (1969 frames, 985 sweeps),
where the translation along the axis is nearly unobservable for a LiDAR alone.

For each: ``slslam lidar run`` (odometry and loop-closed trajectories from one run; map
measurement against the simulator's roadway) and KISS-ICP (``kiss-icp`` from PyPI, its default
configuration with the sweeps' per-point times for deskewing) on the same sweeps. ATE / RPE by evo
(SE3 alignment; RPE of the translation over 1 m of travel) against the body ground truth
(KISS-ICP's LiDAR poses are moved to the body frame with the sensor extrinsics). Writes
benchmarks/results/lidar_slam.json and prints one table.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from common import write_results

SEQUENCES = {"loop2": ("loop", 7150), "straight": ("straight", 1969)}


def _simulate(work: Path, name: str) -> Path:
    from slslam.sim import SimOptions, Simulator

    preset, frames = SEQUENCES[name]
    out = work / name
    manifest = out / "manifest.json"
    if manifest.is_file() and json.loads(manifest.read_text()).get("status") == "complete":
        return out
    Simulator(SimOptions(preset=preset, frames=frames, cameras=False)).write(out, progress=True)
    return out


def _kiss_icp(sequence) -> tuple[np.ndarray, float]:
    from kiss_icp.config import KISSConfig
    from kiss_icp.kiss_icp import KissICP

    config = KISSConfig()
    config.data.deskew = True
    config.mapping.voxel_size = config.data.max_range / 100.0  # KISS-ICP's own default rule
    kiss = KissICP(config)
    poses = np.zeros((len(sequence), 4, 4))
    start = time.perf_counter()
    for k in range(len(sequence)):
        sweep = sequence.sweep(k)
        times = (
            sweep.point_time_s / sequence.scan_period_s
            if sweep.point_time_s is not None
            else np.zeros(len(sweep.points))
        )
        kiss.register_frame(sweep.points[:, :3].astype(np.float64), times)
        poses[k] = kiss.last_pose
    seconds = time.perf_counter() - start
    # LiDAR poses (world = first LiDAR frame) to body poses.
    T_bs = sequence.T_body_sensor
    return T_bs @ poses @ np.linalg.inv(T_bs), seconds


def _errors(sequence, T_world_body: np.ndarray) -> dict:
    from slslam.eval.metrics import compute_ape, compute_rpe
    from slslam.lidar.output import groundtruth_trajectory, to_trajectory

    gt = groundtruth_trajectory(sequence, "body")
    est = to_trajectory(sequence.t_ns, T_world_body)
    ape = compute_ape(gt, est, align="se3", max_diff_s=0.003)
    rpe = compute_rpe(gt, est, delta=1.0, delta_unit="m", align="se3", max_diff_s=0.003)
    return {
        "ape_rmse_m": ape.stats["rmse"],
        "ape_max_m": ape.stats["max"],
        "rpe_1m_rmse_m": rpe.stats["rmse"],
        "rpe_1m_mean_m": rpe.stats["mean"],
    }


def _roadway_truth(name: str) -> dict:
    from slslam.sim.roadway import CrossSection

    truth = {"width_m": CrossSection().width_m}
    if name == "straight":
        truth["length_m"] = 80.0  # centrelines.straight(80.0)
    return truth


def run(work: Path, names: list[str]) -> dict:
    from slslam.lidar.datasets import open_lidar_sequence
    from slslam.lidar.measure import measure_roadway
    from slslam.lidar.output import write_outputs
    from slslam.lidar.slam import LidarSlam

    results = {}
    for name in names:
        folder = _simulate(work, name)
        sequence = open_lidar_sequence(folder)
        preset = SEQUENCES[name][0]
        slam = LidarSlam().run(sequence, progress=True)
        measured = measure_roadway(slam.map_points, slam.T_world_body[:, :3, 3], preset)
        metrics = write_outputs(work / f"{name}_out", sequence, slam, {"map_measurement": measured})
        truth = _roadway_truth(name)
        measurement = {"measured": measured, "truth": truth}
        if measured["width_median_m"] is not None:
            measurement["width_error_pct"] = (
                100 * abs(measured["width_median_m"] - truth["width_m"]) / truth["width_m"]
            )
        if "length_m" in measured:
            measurement["length_error_pct"] = (
                100 * abs(measured["length_m"] - truth["length_m"]) / truth["length_m"]
            )
        kiss_poses, kiss_seconds = _kiss_icp(sequence)
        results[name] = {
            "sweeps": len(sequence),
            "slslam_odometry": _errors(sequence, slam.T_world_body_odometry),
            "slslam_loops": _errors(sequence, slam.T_world_body),
            "kiss_icp": _errors(sequence, kiss_poses),
            "slslam_sweeps_per_second": len(sequence) / slam.seconds,
            "kiss_icp_sweeps_per_second": len(sequence) / kiss_seconds,
            "loops": metrics["loops"] | {"list": None},
            "timing_ms": slam.timing_ms,
            "map": measurement,
        }
    return results


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--work", type=Path, default=Path("/tmp/slslam_lidar_bench"))
    parser.add_argument("--sequences", nargs="+", default=list(SEQUENCES), choices=SEQUENCES)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    try:
        import kiss_icp  # noqa: F401
    except ImportError:
        print("needs kiss-icp: pip install kiss-icp", file=sys.stderr)
        return 1
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    results = run(args.work, args.sequences)
    path = write_results("lidar_slam", {"sequences": results}, args.out)
    print(f"{'sequence':10} {'method':16} {'ATE rmse':>9} {'RPE 1m':>8} {'sweeps/s':>9}")
    for name, r in results.items():
        for method, rate in (
            ("slslam_odometry", "slslam_sweeps_per_second"),
            ("slslam_loops", "slslam_sweeps_per_second"),
            ("kiss_icp", "kiss_icp_sweeps_per_second"),
        ):
            e = r[method]
            print(
                f"{name:10} {method:16} {e['ape_rmse_m']:9.3f} {e['rpe_1m_rmse_m']:8.3f} "
                f"{r[rate]:9.1f}"
            )
        print(
            f"{name:10} loops accepted {r['loops']['accepted']}, false {r['loops']['false']}; "
            f"map {json.dumps(r['map'])}"
        )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
