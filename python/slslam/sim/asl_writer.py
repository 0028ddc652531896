"""Writes a simulated sequence in EuRoC's ASL layout, so every EuRoC tool reads it.

::

    <out>/mav0/cam0|cam1/{data/<t_ns>.png, data.csv, sensor.yaml}
    <out>/mav0/imu0/{data.csv, sensor.yaml}
    <out>/mav0/state_groundtruth_estimate0/data.csv      body poses (ASL ground-truth columns)
    <out>/mav0/lidar0/{data/<t_ns>.bin, data.csv, sensor.yaml, poses_kitti.txt, times.txt}
    <out>/mav0/lidar0/point_time/<t_ns>.bin              per-point time after t_ns [s], float32
    <out>/groundtruth_cam0.tum, groundtruth_body.tum     the same ground truth in TUM format
    <out>/manifest.json                                  preset, seed, parameters, status

Every data file (image, scan, point times, sensor.yaml, the IMU and ground-truth tables, the
manifest) is written under a temporary name and renamed when whole (:mod:`slslam.files`), so no
file under its final name is ever truncated. Index files (data.csv, poses_kitti.txt, times.txt,
groundtruth_cam0.tum) are appended one whole row per frame, after that frame's files are renamed,
and flushed: a run that stops between frames leaves a readable sequence of the frames written
so far, every row naming a complete file.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from slslam._version import __version__
from slslam.files import atomic_output, write_text_atomic

CAMERA_YAML = """%YAML:1.0
# Simulated rectified camera written by slslam {version}.
sensor_type: camera
comment: {comment}
T_BS:
  cols: 4
  rows: 4
  data: [{T}]
rate_hz: {rate}
resolution: [{width}, {height}]
camera_model: pinhole
intrinsics: [{fx}, {fy}, {cx}, {cy}]
distortion_model: radial-tangential
distortion_coefficients: [0.0, 0.0, 0.0, 0.0]
"""

IMU_YAML = """%YAML:1.0
# Simulated IMU written by slslam {version}.
sensor_type: imu
comment: {comment}
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]
rate_hz: {rate}
gyroscope_noise_density: {gnd}
gyroscope_random_walk: {grw}
accelerometer_noise_density: {and_}
accelerometer_random_walk: {arw}
"""

LIDAR_YAML = """%YAML:1.0
# Simulated 16-beam LiDAR written by slslam {version}. Scans: KITTI .bin (float32 x y z i).
sensor_type: lidar
T_BS:
  cols: 4
  rows: 4
  data: [{T}]
rate_hz: {rate}
beams: {beams}
# Each scan is one counter-clockwise sweep starting at its timestamp and lasting 1 / rate_hz; the
# sweep is ray cast in {blocks} azimuth blocks, each from the sensor pose at the block's mid-time,
# and point_time/<t_ns>.bin holds that mid-time after the timestamp [s] for every point.
scan_period_s: {period}
point_time: point_time
"""


def _flat(T: np.ndarray) -> str:
    return ", ".join(f"{v:.9f}" for v in np.asarray(T).ravel())


def quat_wxyz(R: np.ndarray) -> np.ndarray:
    """Quaternions (w, x, y, z) of rotation matrices (N, 3, 3)."""
    return np.roll(Rotation.from_matrix(R).as_quat(), 1, axis=-1)


class AslWriter:
    """Creates the folders and writes each record as it comes."""

    def __init__(self, out: str | Path, lidar: bool, cameras: bool = True):
        self.out = Path(out)
        self.mav0 = self.out / "mav0"
        for sub in ("imu0", "state_groundtruth_estimate0"):
            (self.mav0 / sub).mkdir(parents=True, exist_ok=True)
        self._files = {}
        for cam in ("cam0", "cam1") if cameras else ():
            (self.mav0 / cam / "data").mkdir(parents=True, exist_ok=True)
            self._files[cam] = self._open(self.mav0 / cam / "data.csv", "#timestamp [ns],filename")
        if lidar:
            (self.mav0 / "lidar0" / "data").mkdir(parents=True, exist_ok=True)
            (self.mav0 / "lidar0" / "point_time").mkdir(parents=True, exist_ok=True)
            self._files["lidar0"] = self._open(
                self.mav0 / "lidar0" / "data.csv", "#timestamp [ns],filename"
            )
            self._files["lidar_poses"] = self._open(self.mav0 / "lidar0" / "poses_kitti.txt")
            self._files["lidar_times"] = self._open(self.mav0 / "lidar0" / "times.txt")
        self._files["gt_cam0"] = self._open(
            self.out / "groundtruth_cam0.tum", "# timestamp tx ty tz qx qy qz qw (T_world_cam0)"
        )

    @staticmethod
    def _open(path: Path, header: str | None = None):
        handle = path.open("w", encoding="utf-8")
        if header:
            handle.write(header + "\n")
        return handle

    def _row(self, key: str, text: str) -> None:
        self._files[key].write(text + "\n")
        self._files[key].flush()

    def write_manifest(self, manifest: dict) -> None:
        write_text_atomic(
            self.out / "manifest.json",
            json.dumps({"slslam_version": __version__, **manifest}, indent=2) + "\n",
        )

    def write_calibration(
        self,
        camera,
        T_body_cam0,
        T_body_cam1,
        rate_hz: float,
        imu_rate_hz: float,
        imu_noise,
        lidar=None,
        lidar_rate_hz=10.0,
    ) -> None:
        for name, T in (("cam0", T_body_cam0), ("cam1", T_body_cam1)):
            if not (self.mav0 / name).is_dir():
                continue
            write_text_atomic(
                self.mav0 / name / "sensor.yaml",
                CAMERA_YAML.format(
                    version=__version__,
                    comment=f"slslam simulated {name}",
                    T=_flat(T),
                    rate=rate_hz,
                    width=camera.width,
                    height=camera.height,
                    fx=camera.fx,
                    fy=camera.fx,
                    cx=camera.cx,
                    cy=camera.cy,
                ),
            )
        write_text_atomic(
            self.mav0 / "imu0" / "sensor.yaml",
            IMU_YAML.format(
                version=__version__,
                comment="slslam simulated IMU",
                rate=imu_rate_hz,
                gnd=imu_noise.gyroscope_noise_density,
                grw=imu_noise.gyroscope_random_walk,
                and_=imu_noise.accelerometer_noise_density,
                arw=imu_noise.accelerometer_random_walk,
            ),
        )
        if lidar is not None:
            write_text_atomic(
                self.mav0 / "lidar0" / "sensor.yaml",
                LIDAR_YAML.format(
                    version=__version__,
                    T=_flat(lidar.T_body_lidar),
                    rate=lidar_rate_hz,
                    beams=lidar.beams,
                    blocks=lidar.sweep_blocks,
                    period=1.0 / lidar_rate_hz,
                ),
            )

    def write_stereo(self, t_ns: int, left: np.ndarray, right: np.ndarray, write_image) -> None:
        """Write both images (each renamed when whole), then their index rows (an index row
        never names a missing or partial file)."""
        for key, image in (("cam0", left), ("cam1", right)):
            # the temporary name keeps .png: the encoder picks the format by the suffix
            with atomic_output(self.mav0 / key / "data" / f"{t_ns}.png", keep_suffix=True) as tmp:
                write_image(str(tmp), image)
        for key in ("cam0", "cam1"):
            self._row(key, f"{t_ns},{t_ns}.png")

    def write_camera_pose(self, t_ns: int, T_world_cam0: np.ndarray) -> None:
        q = quat_wxyz(T_world_cam0[:3, :3][None])[0]
        p = T_world_cam0[:3, 3]
        self._row(
            "gt_cam0",
            f"{t_ns * 1e-9:.9f} {p[0]:.9f} {p[1]:.9f} {p[2]:.9f} "
            f"{q[1]:.9f} {q[2]:.9f} {q[3]:.9f} {q[0]:.9f}",
        )

    def write_lidar(
        self, t_ns: int, points: np.ndarray, T_world_lidar: np.ndarray, point_time_s: np.ndarray
    ) -> None:
        """A sweep starting at t_ns: KITTI .bin points, their times after t_ns [s] (float32, same
        order) and the sensor pose at t_ns."""
        lidar0 = self.mav0 / "lidar0"
        with atomic_output(lidar0 / "point_time" / f"{t_ns}.bin") as tmp:
            np.asarray(point_time_s, np.float32).tofile(tmp)
        with atomic_output(lidar0 / "data" / f"{t_ns}.bin") as tmp:
            points.astype(np.float32).tofile(tmp)
        self._row("lidar0", f"{t_ns},{t_ns}.bin")
        self._row("lidar_poses", " ".join(f"{v:.9e}" for v in T_world_lidar[:3].ravel()))
        self._row("lidar_times", f"{t_ns * 1e-9:.9f}")

    def write_imu(self, imu: dict[str, np.ndarray]) -> None:
        table = np.column_stack([imu["gyro"], imu["acc"]])
        with (
            atomic_output(self.mav0 / "imu0" / "data.csv") as tmp,
            tmp.open("w", encoding="utf-8") as f,
        ):
            f.write(
                "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n"
            )
            for t, row in zip(imu["t_ns"], table, strict=True):
                f.write(f"{t}," + ",".join(f"{v:.9f}" for v in row) + "\n")

    def write_body_groundtruth(
        self, t_ns: np.ndarray, T_world_body: np.ndarray, velocity: np.ndarray
    ) -> None:
        """ASL ground truth (pose, velocity, zero biases) and the same poses as TUM."""
        q = quat_wxyz(T_world_body[:, :3, :3])
        p = T_world_body[:, :3, 3]
        zeros = np.zeros((len(t_ns), 6))
        with (
            atomic_output(self.mav0 / "state_groundtruth_estimate0" / "data.csv") as tmp,
            tmp.open("w", encoding="utf-8") as f,
        ):
            f.write(
                "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], "
                "q_RS_y [], q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], "
                "v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], "
                "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
                "b_a_RS_S_z [m s^-2]\n"
            )
            for t, row in zip(t_ns, np.column_stack([p, q, velocity, zeros]), strict=True):
                f.write(f"{t}," + ",".join(f"{v:.9f}" for v in row) + "\n")
        with (
            atomic_output(self.out / "groundtruth_body.tum") as tmp,
            tmp.open("w", encoding="utf-8") as f,
        ):
            f.write("# timestamp tx ty tz qx qy qz qw (T_world_body)\n")
            for t, pi, qi in zip(t_ns, p, q, strict=True):
                f.write(
                    f"{t * 1e-9:.9f} {pi[0]:.9f} {pi[1]:.9f} {pi[2]:.9f} "
                    f"{qi[1]:.9f} {qi[2]:.9f} {qi[3]:.9f} {qi[0]:.9f}\n"
                )

    def close(self) -> None:
        for handle in self._files.values():
            handle.close()
