"""Files of a LiDAR SLAM run: trajectory.tum (and trajectory_odometry.tum), map.ply, metrics.json,
trajectory.png; evo APE/RPE when the sequence has ground truth."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from evo.core.trajectory import PoseTrajectory3D
from scipy.spatial.transform import Rotation

from slslam._version import __version__
from slslam.datasets.trajectory_io import write_tum_ns
from slslam.errors import InputError
from slslam.eval.metrics import compute_ape, compute_rpe
from slslam.files import atomic_output, write_text_atomic
from slslam.lidar.datasets import LidarSequence
from slslam.lidar.slam import LidarSlamResult, _rigid_inverse


def to_trajectory(t_ns: np.ndarray, T: np.ndarray) -> PoseTrajectory3D:
    quat = Rotation.from_matrix(T[:, :3, :3]).as_quat()  # x y z w
    return PoseTrajectory3D(
        positions_xyz=T[:, :3, 3],
        orientations_quat_wxyz=np.roll(quat, 1, axis=1),
        timestamps=t_ns * 1e-9,
    )


def write_ply(path: Path, points: np.ndarray) -> Path:
    """Binary little-endian PLY of float32 x, y, z."""
    pts = np.ascontiguousarray(points, dtype="<f4")
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment slslam LiDAR map (world frame, m)\n"
        f"element vertex {len(pts)}\nproperty float x\nproperty float y\nproperty float z\n"
        "end_header\n"
    )
    with atomic_output(path) as tmp, tmp.open("wb") as f:
        f.write(header.encode("ascii"))
        f.write(pts.tobytes())
    return path


def groundtruth_trajectory(sequence: LidarSequence, frame: str = "body") -> PoseTrajectory3D | None:
    """Ground truth in the frame the estimate is written in (body, or sensor for KITTI)."""
    if sequence.groundtruth is None:
        return None
    t_ns, T = sequence.groundtruth
    if sequence.groundtruth_frame == "body" and frame == "sensor":
        T = T @ sequence.T_body_sensor
    return to_trajectory(t_ns, T)


def loop_errors(sequence: LidarSequence, result: LidarSlamResult) -> list[dict]:
    """Each accepted loop against ground truth: translation [m] and rotation [deg] error of its
    relative pose (a loop off by more than 0.3 m or 2 deg counts as false)."""
    if sequence.groundtruth is None:
        return [{} for _ in result.loops]
    gt_t, gt_T = sequence.groundtruth
    T_bs = sequence.T_body_sensor if sequence.groundtruth_frame == "body" else np.eye(4)
    out = []
    for loop in result.loops:
        tq = result.t_ns[result.keyframes[loop.query]]
        tc = result.t_ns[result.keyframes[loop.candidate]]
        Tq = gt_T[np.argmin(np.abs(gt_t - tq))] @ T_bs
        Tc = gt_T[np.argmin(np.abs(gt_t - tc))] @ T_bs
        E = _rigid_inverse(_rigid_inverse(Tc) @ Tq) @ loop.T_candidate_query
        rot = float(np.degrees(np.linalg.norm(Rotation.from_matrix(E[:3, :3]).as_rotvec())))
        trans = float(np.linalg.norm(E[:3, 3]))
        out.append(
            {
                "translation_error_m": trans,
                "rotation_error_deg": rot,
                "false": bool(trans > 0.3 or rot > 2.0),
            }
        )
    return out


MIN_EVALUATED_SWEEPS = 3  # fewest poses evo's SE3 alignment takes


def evaluate_run(sequence: LidarSequence, result: LidarSlamResult) -> dict:
    """APE / RPE (SE3-aligned; RPE of the translation over 1 m of travel) of the odometry and of
    the loop-closed result."""
    frame = "body" if sequence.groundtruth_frame == "body" else "sensor"
    gt = groundtruth_trajectory(sequence, frame)
    if gt is None:
        return {}
    if len(result.t_ns) < MIN_EVALUATED_SWEEPS:
        raise InputError(
            None,
            f"APE needs at least {MIN_EVALUATED_SWEEPS} sweeps (SE3 alignment of 3 poses); "
            f"the run has {len(result.t_ns)}",
        )
    out: dict[str, dict[str, Any]] = {}
    for name, T in (("odometry", result.T_world_body_odometry), ("slam", result.T_world_body)):
        est = to_trajectory(result.t_ns, T)
        ape = compute_ape(gt, est, align="se3", max_diff_s=0.003)
        try:
            rpe = compute_rpe(gt, est, delta=1.0, delta_unit="m", align="se3", max_diff_s=0.003)
        except InputError:  # a run shorter than 1 m of travel has no pose pair to compare
            rpe = None
        out[name] = {"ape_m": ape.stats, "rpe_1m_m": None if rpe is None else rpe.stats}
        out[name]["_ape"] = ape
    return out


def write_outputs(
    out: Path,
    sequence: LidarSequence,
    result: LidarSlamResult,
    extra: dict | None = None,
    plot: bool = True,
) -> dict:
    """Writes every file of the run (each under a temporary name, renamed when complete);
    returns the metrics dictionary written to metrics.json. A run that stopped early
    (``result.stopped``) is written for the sweeps it processed, with ``completed: false`` and
    the reason in metrics.json; a scoring failure is recorded as ``evaluation_error``."""
    out.mkdir(parents=True, exist_ok=True)
    # exact fixed-point times from the sweeps' integer nanoseconds
    write_tum_ns(out / "trajectory.tum", result.t_ns, result.T_world_body)
    write_tum_ns(out / "trajectory_odometry.tum", result.t_ns, result.T_world_body_odometry)
    write_ply(out / "map.ply", result.map_points)
    evaluation_error = None
    try:
        errors = evaluate_run(sequence, result)
    except Exception as exc:  # evo / numpy on a short or degenerate run: the files come first
        errors, evaluation_error = {}, " ".join(str(exc).split())[:300] or type(exc).__name__
    loops = loop_errors(sequence, result)
    n = len(result.t_ns)
    metrics: dict = {
        "slslam_version": __version__,
        "sequence": sequence.name,
        "sweeps": n,
        "keyframes": len(result.keyframes),
        "seconds": result.seconds,
        "sweeps_per_second": n / max(result.seconds, 1e-9),
        "completed": result.stopped is None,
        "imu": sequence.imu is not None,
        # motion-compensated: deskew on and every sweep with per-point times
        "deskewed": n > 0 and result.deskewed_sweeps == n,
        "deskewed_sweeps": result.deskewed_sweeps,
        "loops": {
            "candidates": result.candidates,
            "accepted": len(result.loops),
            "rejected": result.rejected_loops,
            "false": sum(1 for e in loops if e.get("false")),
            "list": [
                {
                    "query_keyframe": lp.query,
                    "candidate_keyframe": lp.candidate,
                    "scan_context_distance": lp.distance,
                    "fitness": lp.fitness,
                    "inlier_rmse_m": lp.rmse_m,
                    **e,
                }
                for lp, e in zip(result.loops, loops, strict=True)
            ],
        },
        "timing_ms": result.timing_ms,
        "map_points": len(result.map_points),
    }
    for name, stats in errors.items():
        metrics[name] = {k: v for k, v in stats.items() if not k.startswith("_")}
    if evaluation_error is not None:
        metrics["evaluation_error"] = evaluation_error
    if result.stopped is not None:
        metrics["stopped"] = {
            "after_sweeps": n,
            "reason": " ".join(str(result.stopped).split())[:300] or type(result.stopped).__name__,
        }
    if extra:
        metrics.update(extra)
    if plot:
        with atomic_output(out / "trajectory.png") as tmp:
            _plot(tmp, result, errors)
    write_text_atomic(out / "metrics.json", json.dumps(metrics, indent=2) + "\n")
    return metrics


def _plot(path: Path, result: LidarSlamResult, errors: dict) -> None:
    """Left: the map and the trajectory in the run's world frame; right (with ground truth):
    ground truth and the SE3-aligned odometry and loop-closed trajectories."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = 2 if "slam" in errors else 1
    fig, axes = plt.subplots(1, panels, figsize=(8 * panels, 7), squeeze=False)
    ax = axes[0, 0]
    pts = result.map_points[:: max(1, len(result.map_points) // 200000)]
    ax.scatter(pts[:, 0], pts[:, 1], s=0.05, c="0.6", rasterized=True, label="map")
    xyz = result.T_world_body[:, :3, 3]
    ax.plot(xyz[:, 0], xyz[:, 1], color="tab:blue", lw=1.2, label="trajectory")
    ax.set_title("map and trajectory (top view)")
    if panels == 2:
        ax = axes[0, 1]
        ref = errors["slam"]["_ape"].reference.positions_xyz
        est = errors["slam"]["_ape"].estimate_aligned.positions_xyz
        odo = errors["odometry"]["_ape"].estimate_aligned.positions_xyz
        ax.plot(ref[:, 0], ref[:, 1], "k--", lw=1.0, label="ground truth")
        ax.plot(odo[:, 0], odo[:, 1], color="tab:orange", lw=1.0, label="odometry")
        ax.plot(est[:, 0], est[:, 1], color="tab:blue", lw=1.2, label="with loop closure")
        ax.set_title("against ground truth (SE3-aligned)")
    for ax in axes[0]:
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")  # the name may be a temporary one
    plt.close(fig)
