"""LiDAR-inertial SLAM (the LiDAR paper's): odometry in C++ (deskew, scan-to-map registration from
the IMU prediction, fixed-lag IMU smoothing, bounded voxel map), keyframes with Scan Context loop
candidates verified by FPFH + SAC-IA and point-to-plane registration, and a keyframe pose graph.

The per-point work runs in ``slslam._core``; this module orchestrates one sweep at a time.

Frames: ``T_world_body`` is the IMU/body pose (the LiDAR frame for sequences without an IMU);
the world is gravity-aligned at the first sweep. Loop closures correct the keyframe poses; every
sweep is moved with the correction of the keyframe before it (the odometry's own local map is
not re-aligned, as in the ROS map -> odom convention).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from slslam import _core
from slslam.errors import InputError, SlslamError
from slslam.lidar.datasets import LidarSequence
from slslam.progress import progress_bar


@dataclass
class LidarSlamOptions:
    """Back-end options; the odometry's live in the C++ option structs (``odometry``)."""

    keyframe_distance_m: float = 1.0  # a new keyframe after this much travel [m] ...
    keyframe_angle_deg: float = 10.0  # ... or this much rotation [deg]
    loop_closure: bool = True
    loop_submap_keyframes: int = 5  # the candidate's submap: this many keyframes either side
    loop_min_fitness: float = 0.5  # verified loop: inlier fraction at least this [-]
    loop_max_rmse_m: float = 0.08  # ... and inlier RMSE at most this [m]
    loop_drift_fraction: float = 0.05  # a loop may move the query by at most 0.5 m plus this
    # fraction of the path travelled since the candidate (odometry drifts; places repeat) [-]
    loop_drift_floor_rad: float = 0.02  # ... and rotate it by at most this plus
    # loop_drift_fraction rad: a heading error of f rad held over the path L since the candidate
    # displaces the query by about f * L, the translation gate's bound. A curved roadway of
    # constant radius lets registration slide along the arc, rotating about its centre: high
    # fitness, low RMSE, metres and tens of degrees wrong; only the rotation gives it away [rad]
    odometry_sigma_m: float = 0.02  # std. dev. of a keyframe-to-keyframe odometry edge [m]
    odometry_sigma_rad: float = 0.002  # ... and of its rotation [rad]
    loop_sigma_m: float = 0.05  # std. dev. of a loop edge [m]
    loop_sigma_rad: float = 0.01  # ... and of its rotation [rad]
    map_voxel_m: float = 0.1  # voxel of the written map [m]
    odometry: Any = field(default_factory=lambda: _core.LidarOdometryOptions())
    scan_context: Any = field(default_factory=lambda: _core.ScanContextOptions())

    def check(self) -> None:
        for name in (
            "keyframe_distance_m",
            "keyframe_angle_deg",
            "loop_max_rmse_m",
            "loop_drift_floor_rad",
            "odometry_sigma_m",
            "odometry_sigma_rad",
            "loop_sigma_m",
            "loop_sigma_rad",
            "map_voxel_m",
        ):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise InputError(None, f"lidar option {name} must be > 0, got {value!r}")
        if not 0 < self.loop_min_fitness <= 1:
            raise InputError(None, "lidar option loop_min_fitness must be in (0, 1]")
        if self.loop_submap_keyframes < 0:
            raise InputError(None, "lidar option loop_submap_keyframes must be >= 0")
        self.odometry.check()
        self.scan_context.check()


@dataclass
class Loop:
    query: int  # keyframe indices
    candidate: int
    T_candidate_query: np.ndarray  # sensor frames, from registration
    distance: float  # Scan Context distance
    fitness: float
    rmse_m: float


@dataclass
class LidarSlamResult:
    t_ns: np.ndarray  # (N,) sweep start times
    T_world_body_odometry: np.ndarray  # (N, 4, 4) odometry alone
    T_world_body: np.ndarray  # (N, 4, 4) after loop closure
    keyframes: list[int]  # sweep index of every keyframe
    loops: list[Loop]
    rejected_loops: int
    candidates: int
    map_points: np.ndarray  # (M, 3) world, voxelised
    timing_ms: dict[str, dict[str, float]]
    seconds: float
    per_sweep: dict[str, np.ndarray]
    #: sweeps motion-compensated (deskew on and per-point times given)
    deskewed_sweeps: int = 0
    #: what ended the run before its last sweep (bad data, a signal), or None; the fields above
    #: then hold the sweeps before it, every one complete
    stopped: BaseException | None = None


def _rigid_inverse(T: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


def _rotation_angle(R: np.ndarray) -> float:
    return float(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)))


def voxelise(points: np.ndarray, voxel_m: float) -> np.ndarray:
    """First point per voxel (vectorised)."""
    if len(points) == 0:
        return points
    keys = np.floor(points / voxel_m).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    return points[np.sort(first)]


class LidarSlam:
    """Runs a :class:`LidarSequence` sweep by sweep."""

    def __init__(self, options: LidarSlamOptions | None = None) -> None:
        self.options = options or LidarSlamOptions()
        self.options.check()

    def _odometry(self, sequence: LidarSequence) -> Any:
        opts = self.options.odometry
        opts.T_body_sensor = sequence.T_body_sensor
        opts.scan_period_s = sequence.scan_period_s
        if sequence.imu is None:
            opts.use_imu = False
        else:
            noise = sequence.imu.noise
            for ours, theirs in (
                ("gyro_noise_density", "gyroscope_noise_density"),
                ("acc_noise_density", "accelerometer_noise_density"),
                ("gyro_random_walk", "gyroscope_random_walk"),
                ("acc_random_walk", "accelerometer_random_walk"),
            ):
                if theirs in noise:
                    setattr(opts.imu, ours, noise[theirs])
        odometry = _core.LidarOdometry(opts)
        if opts.use_imu:
            imu = sequence.imu
            assert imu is not None  # use_imu is off without one
            # pybind11 takes any sequence for t_ns; the stub's Sequence excludes numpy arrays
            odometry.add_imu(imu.t_ns, imu.gyro, imu.acc)  # type: ignore[arg-type]
        return odometry

    def _verify(
        self, kf_scans: list[np.ndarray], kf_T: list[np.ndarray], q: int, c: int, yaw: float
    ) -> tuple[np.ndarray, float, float] | None:
        """Registers keyframe q onto the submap around keyframe c (in c's sensor frame)."""
        o = self.options
        T_wc_inv = _rigid_inverse(kf_T[c])
        lo, hi = max(0, c - o.loop_submap_keyframes), min(q, c + o.loop_submap_keyframes + 1)
        submap = np.concatenate(
            [
                kf_scans[k] @ (T_wc_inv @ kf_T[k])[:3, :3].T + (T_wc_inv @ kf_T[k])[:3, 3]
                for k in range(lo, hi)
            ]
        )
        source = kf_scans[q]
        T_yaw = np.eye(4)
        T_yaw[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
        rotated = (source @ T_yaw[:3, :3].T).astype(np.float32)
        try:
            coarse = _core.register_clouds(rotated, submap.astype(np.float32))
        except ValueError:
            return None
        T = np.asarray(coarse.transform) @ T_yaw
        match = _core.ScanMatchOptions()
        match.prior_translation_sigma_m = 0.0
        match.prior_rotation_sigma_rad = 0.0
        match.max_iterations = 30
        T, fitness, rmse, _ = _core.match_scan_to_points(source, submap, T, match, 0.5)
        return np.asarray(T), float(fitness), float(rmse)

    def run(
        self,
        sequence: LidarSequence,
        progress: bool = True,
        between_sweeps: Callable[[], None] | None = None,
    ) -> LidarSlamResult:
        """Processes every sweep. ``between_sweeps`` is called before each (it may raise to stop,
        e.g. on a signal). A sweep that fails to read or register (a DatasetError, a
        SlslamError) or a stop ends the run there: the result holds the sweeps before it, with
        ``stopped`` set (nothing processed at all: the exception is raised)."""
        o = self.options
        odometry = self._odometry(sequence)
        T_bs = sequence.T_body_sensor
        scdb = _core.ScanContextDatabase(o.scan_context)
        n = len(sequence)
        poses = np.zeros((n, 4, 4))
        stages = ("deskew_ms", "match_ms", "smoother_ms", "map_ms", "total_ms")
        per_sweep = {k: np.zeros(n) for k in (*stages, "fitness", "degeneracy", "loop_ms")}
        keyframes: list[int] = []
        kf_scans: list[np.ndarray] = []
        kf_T: list[np.ndarray] = []  # odometry T_world_sensor of keyframes
        kf_path_m: list[float] = []
        path_m = 0.0
        loops: list[Loop] = []
        rejected = candidates = 0
        start = time.perf_counter()
        stopped: BaseException | None = None
        done = 0  # sweeps processed completely
        deskewed = 0
        for k in progress_bar(range(n), desc="lidar", unit="sweep", enabled=progress, total=n):
            done = k
            try:
                if between_sweeps is not None:
                    between_sweeps()
                sweep = sequence.sweep(k)
                times: list[float] | np.ndarray = (
                    [] if sweep.point_time_s is None else sweep.point_time_s
                )
                try:
                    r = odometry.process_scan(sweep.t_ns, sweep.points, times)
                except RuntimeError as exc:
                    raise SlslamError(f"{sequence.name}: sweep {k}: {exc}") from None
            except (SlslamError, KeyboardInterrupt) as exc:  # DatasetError is a SlslamError
                if k == 0:
                    raise
                stopped = exc
                break
            done = k + 1
            deskewed += int(bool(o.odometry.deskew) and len(times) > 0)
            poses[k] = r.T_world_body
            for key in stages:
                per_sweep[key][k] = getattr(r, key)
            per_sweep["fitness"][k] = r.fitness
            per_sweep["degeneracy"][k] = r.degeneracy
            T_ws = np.asarray(r.T_world_sensor)
            if k > 0:
                path_m += float(np.linalg.norm(poses[k, :3, 3] - poses[k - 1, :3, 3]))
            if kf_T:
                rel = _rigid_inverse(kf_T[-1]) @ T_ws
                moved = np.linalg.norm(rel[:3, 3]) >= o.keyframe_distance_m
                turned = math.degrees(_rotation_angle(rel[:3, :3])) >= o.keyframe_angle_deg
                if not (moved or turned):
                    continue
            loop_start = time.perf_counter()
            scan = np.asarray(odometry.last_scan())
            keyframes.append(k)
            kf_scans.append(scan)
            kf_T.append(T_ws)
            kf_path_m.append(path_m)
            q = scdb.add(scan)
            if o.loop_closure:
                m = scdb.query(q)
                if m.index >= 0:
                    candidates += 1
                    loop = self._check_loop(kf_scans, kf_T, kf_path_m, q, m)
                    if loop is None:
                        rejected += 1
                    else:
                        loops.append(loop)
            per_sweep["loop_ms"][k] = 1e3 * (time.perf_counter() - loop_start)
        if stopped is not None:  # keep the sweeps before the one that stopped the run
            n = done
            poses = poses[:n]
            per_sweep = {key: values[:n] for key, values in per_sweep.items()}
        graph_start = time.perf_counter()
        corrected = self._close_loops(kf_T, loops)
        graph_ms = 1e3 * (time.perf_counter() - graph_start)
        # Each sweep follows the correction of the keyframe at or before it.
        T_world_body = poses.copy()
        kf_of = np.searchsorted(np.asarray(keyframes), np.arange(n), side="right") - 1
        corrections = [c @ _rigid_inverse(t) for c, t in zip(corrected, kf_T, strict=True)]
        for k in range(n):
            T_world_body[k] = corrections[kf_of[k]] @ poses[k]
        map_points = voxelise(
            np.concatenate(
                [s @ T[:3, :3].T + T[:3, 3] for s, T in zip(kf_scans, corrected, strict=True)]
            ),
            o.map_voxel_m,
        )
        seconds = time.perf_counter() - start
        timing = {
            key: {
                "mean": float(per_sweep[key].mean()),
                "median": float(np.median(per_sweep[key])),
                "max": float(per_sweep[key].max()),
            }
            for key in (*stages, "loop_ms")
        }
        timing["pose_graph_ms"] = {"total": graph_ms}
        del T_bs
        return LidarSlamResult(
            t_ns=sequence.t_ns[:n].copy(),
            T_world_body_odometry=poses,
            T_world_body=T_world_body,
            keyframes=keyframes,
            loops=loops,
            rejected_loops=rejected,
            candidates=candidates,
            map_points=map_points,
            timing_ms=timing,
            seconds=seconds,
            per_sweep=per_sweep,
            deskewed_sweeps=deskewed,
            stopped=stopped,
        )

    def _check_loop(self, kf_scans, kf_T, kf_path_m, q: int, match) -> Loop | None:
        o = self.options
        c = match.index
        verified = self._verify(kf_scans, kf_T, q, c, match.yaw_rad)
        if verified is None:
            return None
        T_cq, fitness, rmse = verified
        if fitness < o.loop_min_fitness or rmse > o.loop_max_rmse_m:
            return None
        # The correction the loop implies must be within what odometry can have drifted.
        T_cq_odometry = _rigid_inverse(kf_T[c]) @ kf_T[q]
        correction = _rigid_inverse(T_cq_odometry) @ T_cq
        if np.linalg.norm(correction[:3, 3]) > 0.5 + o.loop_drift_fraction * (
            kf_path_m[q] - kf_path_m[c]
        ):
            return None
        if _rotation_angle(correction[:3, :3]) > o.loop_drift_floor_rad + o.loop_drift_fraction:
            return None
        return Loop(q, c, T_cq, float(match.distance), fitness, rmse)

    def _close_loops(self, kf_T: list[np.ndarray], loops: list[Loop]) -> list[np.ndarray]:
        if not loops:
            return [T.copy() for T in kf_T]
        o = self.options

        def information(sigma_m: float, sigma_rad: float) -> np.ndarray:
            return np.diag([sigma_m**-2] * 3 + [sigma_rad**-2] * 3)

        a, b, rel, info, is_loop = [], [], [], [], []
        odo_info = information(o.odometry_sigma_m, o.odometry_sigma_rad)
        for i in range(1, len(kf_T)):
            a.append(i - 1)
            b.append(i)
            rel.append(_rigid_inverse(kf_T[i - 1]) @ kf_T[i])
            info.append(odo_info)
            is_loop.append(False)
        loop_info = information(o.loop_sigma_m, o.loop_sigma_rad)
        for loop in loops:
            a.append(loop.candidate)
            b.append(loop.query)
            rel.append(loop.T_candidate_query)
            info.append(loop_info)
            is_loop.append(True)
        return [
            np.asarray(T)
            for T in _core.optimize_lidar_pose_graph(list(kf_T), a, b, rel, info, is_loop)
        ]
