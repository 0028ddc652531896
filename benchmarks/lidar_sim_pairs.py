"""LiDAR registration on simulated 16-beam scan pairs: the seed's two cases.

    python benchmarks/lidar_sim_pairs.py [--runs 3] [--out FILE]

Case A: large translation, small rotation (1.5 m along the roadway, 2 deg yaw); case B: small
translation, large rotation (0.2 m, 25 deg yaw). Scans come from the simulator (straight and loop
roadways, 2 cm range noise) at two poses; the ground truth is their exact relative pose. Prints the
seed's table layout (time, rotation error per axis and total, translation error per axis and total)
for every method. A narrow roadway is the LiDAR paper's degenerate case: along a straight corridor
the translation along the axis is poorly constrained.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from slslam import lidar
from slslam.sim import SimOptions, Simulator

from common import write_results


def _pose(sim: Simulator, t: float, yaw_deg: float = 0.0, forward_m: float = 0.0) -> np.ndarray:
    T = sim.trajectory.pose(np.array([t]))[0] @ sim.lidar.T_body_lidar
    delta = np.eye(4)
    delta[:3, :3] = Rotation.from_euler("z", yaw_deg, degrees=True).as_matrix()
    delta[0, 3] = forward_m
    return T @ delta


def _errors(T_est: np.ndarray, T_true: np.ndarray) -> dict[str, float]:
    E = np.linalg.inv(T_true) @ T_est
    rpy = np.abs(Rotation.from_matrix(E[:3, :3]).as_euler("xyz", degrees=True))
    angle = np.degrees(np.linalg.norm(Rotation.from_matrix(E[:3, :3]).as_rotvec()))
    xyz = np.abs(E[:3, 3])
    return {
        "roll": rpy[0],
        "pitch": rpy[1],
        "yaw": rpy[2],
        "rot_deg": angle,
        "x_m": xyz[0],
        "y_m": xyz[1],
        "z_m": xyz[2],
        "trans_m": float(np.linalg.norm(E[:3, 3])),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    if not lidar.available():
        print("skipped: slslam._core was built without PCL")
        return 0
    rows = []
    cases = {"A_large_translation": (1.5, 2.0), "B_large_rotation": (0.2, 25.0)}
    for preset in ("straight", "loop"):
        sim = Simulator(SimOptions(preset=preset, frames=200, seed=4))
        rng = np.random.default_rng(0)
        for case, (forward, yaw) in cases.items():
            T_target = _pose(sim, 5.0)
            T_source = _pose(sim, 5.0, yaw_deg=yaw, forward_m=forward)
            target = sim.lidar.scan(sim.scene, T_target, rng)
            source = sim.lidar.scan(sim.scene, T_source, rng)
            T_true = np.linalg.inv(T_target) @ T_source  # source points into the target frame
            for method in lidar.METHODS:
                times = []
                for _ in range(args.runs):
                    start = time.perf_counter()
                    T = lidar.register(source, target, method)
                    times.append((time.perf_counter() - start) * 1e3)
                rows.append(
                    {
                        "scene": preset,
                        "case": case,
                        "method": method,
                        "time_ms": float(np.median(times)),
                        **_errors(T, T_true),
                    }
                )
    print(
        f"{'scene':9s}{'case':22s}{'method':17s}{'time_ms':>8s}{'roll':>7s}{'pitch':>7s}"
        f"{'yaw':>7s}{'rot':>7s}{'x_m':>8s}{'y_m':>8s}{'z_m':>8s}{'trans_m':>8s}"
    )
    for r in rows:
        print(
            f"{r['scene']:9s}{r['case']:22s}{r['method']:17s}{r['time_ms']:8.1f}"
            f"{r['roll']:7.3f}{r['pitch']:7.3f}{r['yaw']:7.3f}{r['rot_deg']:7.3f}"
            f"{r['x_m']:8.4f}{r['y_m']:8.4f}{r['z_m']:8.4f}{r['trans_m']:8.4f}"
        )
    print(f"wrote {write_results('lidar_sim_pairs', {'rows': rows}, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
