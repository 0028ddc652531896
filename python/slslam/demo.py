"""The evaluation path without the tracker: generate a mine-like trajectory and score it.

``slslam demo`` writes a ground-truth trajectory of a robot driving once around a shaft-bottom yard
loop (two straights joined by half circles, 0.8 m/s, 20 Hz, small track vibration), and a
*synthetic* estimate of it: the ground truth seen from a rotated, shifted world frame with a
slowly growing heading drift and white position noise, as a visual-odometry front end would give.
The estimate is made up on purpose, from a fixed seed; it exercises reading, association, Umeyama
alignment, APE/RPE and the plots end to end. ``slslam run`` runs the tracker itself, on a
simulated sequence or a dataset.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from evo.core.trajectory import PoseTrajectory3D
from scipy.spatial.transform import Rotation

from slslam.datasets.trajectory_io import write_trajectory
from slslam.eval.report import Evaluation, evaluate


@dataclass(frozen=True)
class DemoOptions:
    """Shape of the generated loop and of the estimate's errors."""

    straight_m: float = 30.0  # length of each straight [m]
    radius_m: float = 8.0  # radius of the turns [m]
    speed_mps: float = 0.8  # robot speed [m/s]
    rate_hz: float = 20.0  # pose rate [Hz]
    drift_deg_per_m: float = 0.02  # heading drift of the estimate [deg per metre travelled]
    noise_m: float = 0.01  # white position noise of the estimate, per axis [m]
    seed: int = 7


def loop_groundtruth(options: DemoOptions = DemoOptions()) -> PoseTrajectory3D:
    """Camera poses ``T_world_cam`` (z forward, x right, y down) along a closed yard loop."""
    perimeter = 2 * options.straight_m + 2 * np.pi * options.radius_m
    n = int(perimeter / options.speed_mps * options.rate_hz)
    s = np.linspace(0.0, perimeter, n, endpoint=False)
    L, r = options.straight_m, options.radius_m
    x, y, yaw = np.empty(n), np.empty(n), np.empty(n)
    for lo, hi, fn in (
        (0, L, lambda u: (u, 0.0 * u, 0.0 * u)),
        (
            L,
            L + np.pi * r,
            lambda u: (L + r * np.sin((u - L) / r), r - r * np.cos((u - L) / r), (u - L) / r),
        ),
        (
            L + np.pi * r,
            2 * L + np.pi * r,
            lambda u: (L - (u - L - np.pi * r), 2 * r + 0.0 * u, np.pi + 0.0 * u),
        ),
        (
            2 * L + np.pi * r,
            perimeter,
            lambda u: (
                -r * np.sin((u - 2 * L - np.pi * r) / r),
                r + r * np.cos((u - 2 * L - np.pi * r) / r),
                np.pi + (u - 2 * L - np.pi * r) / r,
            ),
        ),
    ):
        sel = (s >= lo) & (s < hi)
        x[sel], y[sel], yaw[sel] = fn(s[sel])
    t = s / options.speed_mps
    z = 1.2 + 0.004 * np.sin(2 * np.pi * 3.1 * t)  # camera height with track vibration [m]
    # Body heading yaw (z up); the camera looks along the body x axis.
    R_world_body = Rotation.from_euler("z", yaw[:, None])
    R_body_cam = Rotation.from_matrix([[0, 0, 1], [-1, 0, 0], [0, -1, 0]])
    quat_xyzw = (R_world_body * R_body_cam).as_quat()
    quat_wxyz = np.roll(quat_xyzw, 1, axis=1)
    return PoseTrajectory3D(np.column_stack([x, y, z]), quat_wxyz, 1.4e9 + t)


def synthetic_estimate(
    gt: PoseTrajectory3D, options: DemoOptions = DemoOptions()
) -> PoseTrajectory3D:
    """A drifting, noisy copy of ``gt`` expressed in another (rotated, shifted) world frame."""
    rng = np.random.default_rng(options.seed)
    xyz = gt.positions_xyz
    travelled = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(xyz, axis=0), axis=1))])
    drift = Rotation.from_euler("z", (np.deg2rad(options.drift_deg_per_m) * travelled)[:, None])
    start = xyz[0]
    drifted = drift.apply(xyz - start) + start + rng.normal(0, options.noise_m, xyz.shape)
    R_frame = Rotation.from_euler("zyx", [40.0, 3.0, -2.0], degrees=True)
    t_frame = np.array([5.0, -3.0, 0.5])
    rot = R_frame * drift * Rotation.from_quat(np.roll(gt.orientations_quat_wxyz, -1, axis=1))
    return PoseTrajectory3D(
        R_frame.apply(drifted) + t_frame, np.roll(rot.as_quat(), 1, axis=1), gt.timestamps.copy()
    )


def run_demo(out_dir: str | Path, options: DemoOptions = DemoOptions()) -> Evaluation:
    """Write ``groundtruth.tum``, ``estimate.tum``, ``metrics.json``, ``ape.png`` to ``out_dir``."""
    out_dir = Path(out_dir)
    gt = loop_groundtruth(options)
    est = synthetic_estimate(gt, options)
    gt_path = write_trajectory(out_dir / "groundtruth.tum", gt)
    est_path = write_trajectory(out_dir / "estimate.tum", est)
    return evaluate(est_path, gt_path, out_dir=out_dir, align="se3", rpe_delta=1.0, rpe_unit="m")
