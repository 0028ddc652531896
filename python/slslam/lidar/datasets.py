"""LiDAR + IMU sequences for ``slslam lidar run``: the simulator's ASL layout and KITTI odometry.

ASL (``slslam sim``, EuRoC-like)::

    mav0/lidar0/{data.csv, data/<t_ns>.bin, sensor.yaml[, point_time/<t_ns>.bin]}
    mav0/imu0/{data.csv, sensor.yaml}
    mav0/state_groundtruth_estimate0/data.csv   (optional ground truth, body frame)

``data/<t_ns>.bin`` are KITTI float32 (x, y, z, intensity) records in the sensor frame;
``point_time/<t_ns>.bin`` holds one float32 per point, its time after ``t_ns`` [s] (the
simulator writes it; without it sweeps are not deskewed). ``sensor.yaml`` gives ``T_BS`` (the
LiDAR in the IMU/body frame) and ``scan_period_s``.

KITTI odometry: ``velodyne/<frame>.bin`` and ``times.txt`` [s], with optional ``poses.txt``
(camera poses) and ``calib.txt`` (``Tr``) for ground truth; no IMU, so LiDAR-only odometry.

ROS bags (ROS1 ``.bag``, ROS2 folder or its ``.db3`` / ``.mcap``), read with ``rosbags`` (no ROS
install): ``sensor_msgs/PointCloud2`` sweeps and optionally ``sensor_msgs/Imu``
(:class:`RosbagLidarSequence`). A cloud needs float ``x``, ``y``, ``z``; ``intensity`` is kept
when present. Per-point time, when the cloud has it, is read from the field drivers use: ``t``
(Ouster: uint32 ns after the stamp), ``time`` (Velodyne: float s after the stamp, negative
when the stamp is the sweep's end) or ``timestamp`` (Hesai and others: float64 absolute s). The
sweep then starts at its earliest point, and each point's time counts from there; without such
a field sweeps are not deskewed. Non-finite points (organised clouds' empty pixels) are dropped.
The LiDAR-to-IMU transform is not in a bag: pass ``T_body_sensor`` (default identity).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from slslam.errors import DatasetError
from slslam.files import require_regular_file, special_file_kind
from slslam.yaml_io import read_yaml, short_repr

#: Bounds on what a sequence may hold; a value beyond them is a corrupt or mistaken file:
#: per-point times lie in [0, MAX_POINT_TIME_PERIODS * scan period] after the sweep start (a
#: sweep lasts one period; the margin allows a driver's jitter) ...
MAX_POINT_TIME_PERIODS = 1.5
#: ... point coordinates within MAX_RANGE_M of the sensor [m] (LiDARs reach a few hundred m) ...
MAX_RANGE_M = 1e4
#: ... the LiDAR within MAX_LEVER_ARM_M of the IMU in T_BS [m] ...
MAX_LEVER_ARM_M = 100.0
#: ... IMU noise densities and random walks at most this (SI units; real ones are < 0.1) ...
MAX_IMU_NOISE = 10.0
#: ... the scan rate in [MIN_RATE_HZ, MAX_RATE_HZ] (scan_period_s within the inverse) ...
MIN_RATE_HZ, MAX_RATE_HZ = 1.0, 1000.0
#: ... and timestamps [ns] in [0, 2^63): int64 nanoseconds since 1970.
MAX_T_NS = 2**63 - 1
#: a rotation's |R^T R - I| and |det R - 1| at most this; T_BS's bottom row [0, 0, 0, 1] within it
ROTATION_TOLERANCE = 1e-6
#: a ground-truth quaternion's norm within 1 +- this (written with 6 or more digits)
QUATERNION_NORM_TOLERANCE = 1e-2


@dataclass
class Sweep:
    """One LiDAR sweep: start time, points (N, 4) float32 in the sensor frame, per-point times
    after the start [s] (None: unknown)."""

    t_ns: int
    points: np.ndarray
    point_time_s: np.ndarray | None


@dataclass
class Imu:
    """IMU samples: t_ns (N,) int64, gyro (N, 3) [rad/s], acc (N, 3) [m/s^2], body frame."""

    t_ns: np.ndarray
    gyro: np.ndarray
    acc: np.ndarray
    noise: dict[str, float]


def check_points(points: np.ndarray, where: str | Path) -> None:
    """x, y, z finite and within MAX_RANGE_M of the sensor; DatasetError naming ``where``."""
    xyz = points[:, :3]
    bad = ~np.isfinite(xyz).all(axis=1)
    if bad.any():
        raise DatasetError(
            where, f"point {int(np.flatnonzero(bad)[0])}: NaN or infinite coordinates"
        )
    far = np.abs(xyz).max(axis=1) > MAX_RANGE_M
    if far.any():
        i = int(np.flatnonzero(far)[0])
        raise DatasetError(
            where,
            f"point {i} lies {float(np.abs(xyz[i]).max()):.3g} m out (at most {MAX_RANGE_M:g})",
        )


def check_point_times(times_s: np.ndarray, scan_period_s: float, where: str | Path) -> None:
    """Per-point times after the sweep start [s] are finite and in [0, MAX_POINT_TIME_PERIODS *
    scan_period_s]; DatasetError naming ``where`` and the first point outside."""
    limit = MAX_POINT_TIME_PERIODS * scan_period_s
    bad = ~(np.isfinite(times_s) & (times_s >= 0) & (times_s <= limit))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise DatasetError(
            where,
            f"point {i} has time {float(times_s[i]):.6g} s: per-point times must lie in [0, "
            f"{limit:.6g}] s ({MAX_POINT_TIME_PERIODS:g} x the scan period "
            f"{scan_period_s:.6g} s)",
        )


def check_t_ns(values: np.ndarray, where: str | Path, what: str = "timestamps") -> np.ndarray:
    """Timestamps [ns] read as float64 (a CSV column): finite, whole, in [0, MAX_T_NS], and
    increasing; returned as int64. DatasetError naming ``where`` and the row otherwise."""
    bad = ~(np.isfinite(values) & (values >= 0) & (values < float(MAX_T_NS)))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise DatasetError(
            where, f"row {i + 1}: {what} {short_repr(float(values[i]))} not in [0, 2^63) ns"
        )
    t_ns = values.astype(np.int64)
    back = np.flatnonzero(np.diff(t_ns) <= 0)
    if back.size:
        raise DatasetError(where, f"row {int(back[0]) + 2}: {what} must increase")
    return t_ns


class LidarSequence:
    """Index of a sequence's sweeps; sweeps are read one at a time when iterated."""

    def __init__(
        self,
        name: str,
        t_ns: np.ndarray,
        scan_paths: list[Path],
        time_paths: list[Path | None],
        T_body_sensor: np.ndarray,
        scan_period_s: float,
        imu: Imu | None,
        groundtruth: tuple[np.ndarray, np.ndarray] | None,
        groundtruth_frame: str,
    ) -> None:
        self.name = name
        self.t_ns = t_ns
        self.scan_paths = scan_paths
        self.time_paths = time_paths
        self.T_body_sensor = T_body_sensor
        self.scan_period_s = scan_period_s
        self.imu = imu
        #: (t_ns (M,), T_world_frame (M, 4, 4)) in ``groundtruth_frame`` ("body" or "sensor")
        self.groundtruth = groundtruth
        self.groundtruth_frame = groundtruth_frame

    def __len__(self) -> int:
        return len(self.scan_paths)

    def truncate(self, count: int) -> None:
        """Keep only the first ``count`` sweeps."""
        self.scan_paths = self.scan_paths[:count]
        self.time_paths = self.time_paths[:count]
        self.t_ns = self.t_ns[:count]

    def sweep(self, k: int) -> Sweep:
        path = require_regular_file(self.scan_paths[k], DatasetError, "scan file")
        size = path.stat().st_size
        if size % 16 or size == 0:
            raise DatasetError(path, f"{size} bytes: not a whole number of 16-byte points")
        points = np.fromfile(path, dtype=np.float32).reshape(-1, 4)
        times = None
        time_file = self.time_paths[k]
        if time_file is not None:
            time_path = require_regular_file(time_file, DatasetError, "point-time file")
            times = np.fromfile(time_path, dtype=np.float32).astype(np.float64)
            if times.shape[0] != points.shape[0]:
                raise DatasetError(
                    time_path, f"{times.shape[0]} point times for {points.shape[0]} points"
                )
            check_point_times(times, self.scan_period_s, time_path)
        check_points(points, path)
        return Sweep(int(self.t_ns[k]), points, times)

    def __iter__(self) -> Iterator[Sweep]:
        for k in range(len(self)):
            yield self.sweep(k)


def _read_csv(path: Path, columns: int) -> np.ndarray:
    require_regular_file(path, DatasetError)
    try:
        table = np.loadtxt(path, delimiter=",", comments="#", ndmin=2, dtype=np.float64)
    except ValueError as exc:  # also UnicodeDecodeError: a binary file
        raise DatasetError(path, f"not a numeric CSV ({short_repr(str(exc), 120)})") from None
    if table.size == 0 or table.shape[1] < columns:
        raise DatasetError(path, f"expected at least {columns} columns and one row")
    bad = ~np.isfinite(table[:, :columns]).all(axis=1)
    if bad.any():
        raise DatasetError(path, f"row {int(np.flatnonzero(bad)[0]) + 1}: NaN or infinite value")
    return table


def _sensor_yaml(path: Path) -> dict:
    data = read_yaml(path, DatasetError, strip_opencv_header=True)
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise DatasetError(path, f"expected a YAML mapping, got {type(data).__name__}")
    return data


def _number(data: dict, key: str, path: Path, low: float, high: float) -> float | None:
    """``data[key]`` as a float in [low, high] (None when absent); a bool, string or
    out-of-range value is a DatasetError naming the file and key."""
    if key not in data:
        return None
    value = data[key]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise DatasetError(path, f"'{key}' must be a number, got {short_repr(value)}")
    try:
        number = float(value)
    except OverflowError:
        number = float("inf")
    if not (np.isfinite(number) and low <= number <= high):
        raise DatasetError(path, f"'{key}' must be in [{low:g}, {high:g}], got {short_repr(value)}")
    return number


def _T_BS(path: Path, data: dict) -> np.ndarray:
    """``T_BS`` (sensor in body, 4 x 4 row-major): finite numbers, a proper rotation (R^T R = I,
    det R = +1, not a reflection), bottom row [0, 0, 0, 1], lever arm within MAX_LEVER_ARM_M."""
    entry = data.get("T_BS")
    if entry is None:
        raise DatasetError(path, "missing key 'T_BS: data'")
    values = entry.get("data") if isinstance(entry, dict) else None
    if values is None:
        raise DatasetError(path, "missing key 'T_BS: data'")
    if (
        not isinstance(values, list)
        or len(values) != 16
        or any(isinstance(v, bool) or not isinstance(v, int | float) for v in values)
    ):
        raise DatasetError(path, "'T_BS: data' must hold 16 numbers")
    try:
        T = np.array(values, dtype=np.float64).reshape(4, 4)
    except OverflowError:
        raise DatasetError(path, "'T_BS: data' holds a number too large") from None
    if not np.isfinite(T).all():
        raise DatasetError(path, "'T_BS: data' holds NaN or infinite values")
    if np.abs(T[3] - [0.0, 0.0, 0.0, 1.0]).max() > ROTATION_TOLERANCE:
        raise DatasetError(path, f"'T_BS' bottom row is {T[3].tolist()}, not [0, 0, 0, 1]")
    R = T[:3, :3]
    if np.abs(R.T @ R - np.eye(3)).max() > ROTATION_TOLERANCE:
        raise DatasetError(path, "'T_BS' rotation is not orthonormal: not a rigid transform")
    if abs(np.linalg.det(R) - 1.0) > ROTATION_TOLERANCE:
        raise DatasetError(path, "'T_BS' rotation has determinant -1: a reflection, not a rotation")
    if np.linalg.norm(T[:3, 3]) > MAX_LEVER_ARM_M:
        raise DatasetError(
            path,
            f"'T_BS' translation is {np.linalg.norm(T[:3, 3]):.3g} m (at most {MAX_LEVER_ARM_M:g})",
        )
    return T


IMU_NOISE_KEYS = (
    "gyroscope_noise_density",
    "gyroscope_random_walk",
    "accelerometer_noise_density",
    "accelerometer_random_walk",
)


def _imu(mav0: Path) -> Imu:
    path = mav0 / "imu0" / "data.csv"
    table = _read_csv(path, 7)
    t_ns = check_t_ns(table[:, 0], path)
    noise: dict[str, float] = {}
    yaml_path = mav0 / "imu0" / "sensor.yaml"
    if special_file_kind(yaml_path) != "missing":
        data = _sensor_yaml(yaml_path)
        for key in IMU_NOISE_KEYS:
            value = _number(data, key, yaml_path, 0.0, MAX_IMU_NOISE)
            if value is not None:
                noise[key] = value
    return Imu(t_ns, table[:, 1:4].copy(), table[:, 4:7].copy(), noise)


def _asl_groundtruth(mav0: Path) -> tuple[np.ndarray, np.ndarray] | None:
    path = mav0 / "state_groundtruth_estimate0" / "data.csv"
    if special_file_kind(path) == "missing":
        return None
    from scipy.spatial.transform import Rotation

    table = _read_csv(path, 8)  # every row finite
    t_ns = check_t_ns(table[:, 0], path)
    norm = np.linalg.norm(table[:, 4:8], axis=1)
    off = np.abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE
    if off.any():
        i = int(np.flatnonzero(off)[0])
        raise DatasetError(
            path, f"row {i + 1}: quaternion norm {norm[i]:.6g} (a unit quaternion expected)"
        )
    T = np.tile(np.eye(4), (len(table), 1, 1))
    T[:, :3, 3] = table[:, 1:4]
    T[:, :3, :3] = Rotation.from_quat(table[:, [5, 6, 7, 4]]).as_matrix()  # w x y z -> x y z w
    return t_ns, T


def _scan_period(path: Path, data: dict) -> float:
    """``scan_period_s``, else 1 / ``rate_hz``, else 0.1 s; both checked against the rate bounds."""
    period = _number(data, "scan_period_s", path, 1.0 / MAX_RATE_HZ, 1.0 / MIN_RATE_HZ)
    rate = _number(data, "rate_hz", path, MIN_RATE_HZ, MAX_RATE_HZ)
    if period is not None:
        return period
    return 1.0 / rate if rate is not None else 0.1


def open_asl(path: Path) -> LidarSequence:
    mav0 = path / "mav0" if (path / "mav0").is_dir() else path
    lidar0 = mav0 / "lidar0"
    index = lidar0 / "data.csv"
    if special_file_kind(index) == "missing":
        raise DatasetError(path, "not a LiDAR ASL folder: expected mav0/lidar0/data.csv")
    require_regular_file(index, DatasetError, "CSV file")
    try:
        text = index.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise DatasetError(index, f"not UTF-8 text (byte {exc.start}): not a CSV") from None
    rows = [
        (number, line.split(","))
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.startswith("#")
    ]
    if not rows:
        raise DatasetError(index, "lists no scans")
    for number, row in rows:
        name = row[1].strip() if len(row) >= 2 else ""
        if len(row) != 2 or not name or "/" in name or "\\" in name or name in (".", ".."):
            raise DatasetError(index, f"line {number}: rows must be '<t_ns>,<file name>'")
        if not row[0].strip().isdigit() or int(row[0]) > MAX_T_NS:
            raise DatasetError(
                index,
                f"line {number}: timestamp {short_repr(row[0].strip(), 30)} is not an "
                "integer in [0, 2^63) ns",
            )
    t_ns = np.array([int(r[0]) for _, r in rows], dtype=np.int64)
    back = np.flatnonzero(np.diff(t_ns) <= 0)
    if back.size:
        raise DatasetError(index, f"line {rows[int(back[0]) + 1][0]}: timestamps must increase")
    scans = [lidar0 / "data" / r[1].strip() for _, r in rows]
    for scan in scans:
        kind = special_file_kind(scan)
        if kind == "missing":
            raise DatasetError(scan, f"scan file listed in {index} not found")
        if kind is not None:
            raise DatasetError(scan, f"scan file listed in {index} is {kind}")
    times: list[Path | None] = [lidar0 / "point_time" / p.name for p in scans]
    if not all(t is not None and t.is_file() for t in times):
        times = [None] * len(scans)
    sensor_path = lidar0 / "sensor.yaml"
    sensor = _sensor_yaml(sensor_path)
    period = _scan_period(sensor_path, sensor)
    imu = _imu(mav0) if special_file_kind(mav0 / "imu0" / "data.csv") != "missing" else None
    return LidarSequence(
        name=path.name,
        t_ns=t_ns,
        scan_paths=scans,
        time_paths=times,
        T_body_sensor=_T_BS(sensor_path, sensor),
        scan_period_s=period,
        imu=imu,
        groundtruth=_asl_groundtruth(mav0),
        groundtruth_frame="body",
    )


def open_kitti(path: Path) -> LidarSequence:
    velodyne = path / "velodyne"
    scans = sorted(velodyne.glob("*.bin"))
    if not scans:
        raise DatasetError(path, "not a KITTI sequence: expected velodyne/*.bin")
    times_path = path / "times.txt"
    if not times_path.is_file():
        raise DatasetError(times_path, "file not found (one time [s] per scan)")
    require_regular_file(times_path, DatasetError)
    try:
        times = np.loadtxt(times_path, ndmin=1, dtype=float)
    except ValueError as exc:
        raise DatasetError(
            times_path, f"not a list of times ({short_repr(str(exc), 120)})"
        ) from None
    if times.ndim != 1 or len(times) != len(scans):
        raise DatasetError(times_path, f"{times.size} times for {len(scans)} scans (one a line)")
    t_ns = check_t_ns(np.round(times * 1e9), times_path, "times")
    groundtruth = None
    if (path / "poses.txt").is_file() and (path / "calib.txt").is_file():
        from slslam import _core  # noqa: F401  (the readers live in the C++ core)
        from slslam.lidar.evaluation import kitti_velodyne_poses

        groundtruth = (t_ns, kitti_velodyne_poses(path / "poses.txt", path / "calib.txt"))
    return LidarSequence(
        name=path.name,
        t_ns=t_ns,
        scan_paths=scans,
        time_paths=[None] * len(scans),
        T_body_sensor=np.eye(4),
        scan_period_s=0.1,
        imu=None,
        groundtruth=groundtruth,
        groundtruth_frame="sensor",
    )


POINTCLOUD2_TYPE = "sensor_msgs/msg/PointCloud2"
IMU_TYPE = "sensor_msgs/msg/Imu"
#: sensor_msgs/PointField datatype -> numpy type
_POINTFIELD_TYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}


def decode_pointcloud2(msg, where: str | Path) -> tuple[int, np.ndarray, np.ndarray | None]:
    """A PointCloud2 message as (sweep start t_ns, points (N, 4) float32 x y z intensity,
    per-point times after the start [s] or None); see the module docstring for the time fields."""
    fields = {f.name: f for f in msg.fields}
    missing = [name for name in ("x", "y", "z") if name not in fields]
    if missing:
        raise DatasetError(
            where, f"PointCloud2 without field(s) {', '.join(missing)} (has {', '.join(fields)})"
        )
    count = int(msg.width) * int(msg.height)
    step = int(msg.point_step)
    data = np.frombuffer(bytes(msg.data), dtype=np.uint8)
    if count == 0 or step <= 0 or data.size < count * step:
        raise DatasetError(
            where,
            f"PointCloud2 of {count} points of {step} bytes holds {data.size} bytes (truncated)",
        )
    order = ">" if msg.is_bigendian else "<"
    used = [n for n in ("x", "y", "z", "intensity", "t", "time", "timestamp") if n in fields]
    for name in used:
        kind = fields[name].datatype
        if kind not in _POINTFIELD_TYPES:
            raise DatasetError(where, f"PointCloud2 field {name!r}: unknown datatype {kind}")
        end = int(fields[name].offset) + np.dtype(_POINTFIELD_TYPES[kind]).itemsize
        if int(fields[name].offset) < 0 or end > step:
            raise DatasetError(
                where, f"PointCloud2 field {name!r} ends at byte {end}, past point_step {step}"
            )
    for name in ("x", "y", "z"):
        if _POINTFIELD_TYPES[fields[name].datatype][0] != "f":
            raise DatasetError(where, f"PointCloud2 field {name!r} is not a float")
    dtype = np.dtype(
        {
            "names": used,
            "formats": [order + _POINTFIELD_TYPES[fields[n].datatype] for n in used],
            "offsets": [int(fields[n].offset) for n in used],
            "itemsize": step,
        }
    )
    cloud = np.frombuffer(data[: count * step], dtype=dtype, count=count)
    points = np.zeros((count, 4), dtype=np.float32)
    for i, name in enumerate(("x", "y", "z")):
        points[:, i] = cloud[name]
    if "intensity" in used:
        points[:, 3] = cloud["intensity"]
    from slslam.datasets.rosbag import _stamp_ns

    stamp_ns = _stamp_ns(msg, str(where))
    offset_s = None
    if "t" in used:
        offset_s = cloud["t"].astype(np.float64) * 1e-9
    elif "time" in used:
        offset_s = cloud["time"].astype(np.float64)
    elif "timestamp" in used:
        offset_s = cloud["timestamp"].astype(np.float64) - stamp_ns * 1e-9
    keep = np.isfinite(points[:, :3]).all(axis=1)
    if offset_s is not None:
        keep &= np.isfinite(offset_s)
    points = points[keep]
    if points.shape[0] == 0:
        raise DatasetError(where, "PointCloud2 without a finite point")
    check_points(points, where)
    if offset_s is None:
        return stamp_ns, points, None
    offset_s = offset_s[keep]
    # Times count from the stamp, unless points precede it (a stamp at the sweep's end): then
    # from the earliest point.
    first = min(0.0, float(offset_s.min()))
    return stamp_ns + round(first * 1e9), points, offset_s - first


class RosbagLidarSequence(LidarSequence):
    """LiDAR sweeps (and IMU) from a ROS bag, read one sweep at a time (module docstring).

    Args:
        path: ROS1 ``.bag`` file, ROS2 bag folder or its storage file.
        lidar_topic, imu_topic: None picks the bag's only PointCloud2 / Imu topic.
        T_body_sensor: the LiDAR in the IMU (body) frame, 4 x 4.
        use_imu: False ignores the bag's IMU.
    """

    def __init__(
        self,
        path: str | Path,
        lidar_topic: str | None = None,
        imu_topic: str | None = None,
        T_body_sensor: np.ndarray | None = None,
        use_imu: bool = True,
    ) -> None:
        from slslam.datasets.rosbag import (
            _check_stamps,
            _messages,
            _open_reader,
            _stamp_ns,
            _Where,
            deserialize,
            read_imu,
        )

        path = Path(path)
        self._path = path
        self._reader = _open_reader(path)
        topics = {c.topic: c.msgtype for c in self._reader.connections}
        lidar_topic = self._pick(path, topics, lidar_topic, POINTCLOUD2_TYPE, required=True)
        imu_topic = (
            self._pick(path, topics, imu_topic, IMU_TYPE, required=False) if use_imu else None
        )
        self._connections = [c for c in self._reader.connections if c.topic == lidar_topic]
        self._where = _Where(path, lidar_topic)
        bag_times, stamps = [], []
        for i, (connection, bag_time, raw) in enumerate(
            _messages(self._reader, self._connections, path)
        ):
            msg = deserialize(self._reader, raw, connection.msgtype, self._where(i))
            bag_times.append(int(bag_time))
            stamps.append(_stamp_ns(msg, self._where(i)))
        if not stamps:
            raise DatasetError(path, f"{lidar_topic}: no messages")
        t_ns = np.asarray(stamps, dtype=np.int64)
        _check_stamps(t_ns, self._where)  # in bag order: increasing, not all zero
        self._bag_times = bag_times
        self._indices = list(range(len(bag_times)))  # message index in the topic, per sweep
        period = float(np.median(np.diff(t_ns))) * 1e-9 if len(t_ns) > 1 else 0.1
        imu = None
        if imu_topic is not None:
            samples = read_imu(self._reader, imu_topic, path)
            if len(samples["t_ns"]) < 2:
                raise DatasetError(path, f"{imu_topic}: needs at least 2 messages")
            imu = Imu(samples["t_ns"], samples["gyro"], samples["acc"], {})
        T = np.eye(4) if T_body_sensor is None else np.asarray(T_body_sensor, dtype=float)
        super().__init__(
            name=path.stem if path.is_file() else path.name,
            t_ns=t_ns,
            scan_paths=[path] * len(t_ns),
            time_paths=[None] * len(t_ns),
            T_body_sensor=T,
            scan_period_s=min(max(period, 1e-3), 1.0),
            imu=imu,
            groundtruth=None,
            groundtruth_frame="body",
        )
        self.lidar_topic, self.imu_topic = lidar_topic, imu_topic

    @staticmethod
    def _pick(path: Path, topics: dict[str, str], topic: str | None, msgtype: str, required: bool):
        if topic is not None:
            if topics.get(topic) != msgtype:
                raise DatasetError(
                    path,
                    f"no {msgtype} topic {topic!r} (topics: {', '.join(sorted(topics)) or 'none'})",
                )
            return topic
        found = sorted(t for t, kind in topics.items() if kind == msgtype)
        if len(found) == 1:
            return found[0]
        if not found and not required:
            return None
        raise DatasetError(
            path,
            f"{'no' if not found else len(found)} {msgtype} topics in the bag "
            f"({', '.join(found) or 'topics: ' + ', '.join(sorted(topics))}): name one",
        )

    def sweep(self, k: int) -> Sweep:
        from slslam.datasets.rosbag import _messages, deserialize

        bag_time = self._bag_times[k]
        where = self._where(self._indices[k])
        for connection, _, raw in _messages(
            self._reader, self._connections, self._path, start=bag_time, stop=bag_time + 1
        ):
            msg = deserialize(self._reader, raw, connection.msgtype, where)
            t_ns, points, times = decode_pointcloud2(msg, where)
            if times is not None:
                check_point_times(times, self.scan_period_s, where)
            return Sweep(t_ns, points, times)
        raise DatasetError(where, "message could not be read back")

    def truncate(self, count: int) -> None:
        super().truncate(count)
        self._bag_times = self._bag_times[:count]
        self._indices = self._indices[:count]


def open_lidar_sequence(
    path: str | Path, lidar_topic: str | None = None, imu_topic: str | None = None
) -> LidarSequence:
    """Opens an ASL (simulator) or KITTI odometry sequence, or a ROS bag; raises DatasetError
    naming the path."""
    from slslam.datasets.rosbag import is_rosbag

    path = Path(path)
    if is_rosbag(path):
        return RosbagLidarSequence(path, lidar_topic, imu_topic)
    if not path.is_dir():
        raise DatasetError(path, "dataset folder not found")
    if (path / "velodyne").is_dir():
        return open_kitti(path)
    return open_asl(path)
