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
import yaml

from slslam.errors import DatasetError


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
        path = self.scan_paths[k]
        size = path.stat().st_size
        if size % 16 or size == 0:
            raise DatasetError(path, f"{size} bytes: not a whole number of 16-byte points")
        points = np.fromfile(path, dtype=np.float32).reshape(-1, 4)
        times = None
        if self.time_paths[k] is not None:
            times = np.fromfile(self.time_paths[k], dtype=np.float32).astype(np.float64)
            if times.shape[0] != points.shape[0]:
                raise DatasetError(
                    self.time_paths[k], f"{times.shape[0]} point times for {points.shape[0]} points"
                )
        if not np.isfinite(points[:, :3]).all():
            raise DatasetError(path, "holds NaN or infinite coordinates")
        return Sweep(int(self.t_ns[k]), points, times)

    def __iter__(self) -> Iterator[Sweep]:
        for k in range(len(self)):
            yield self.sweep(k)


def _read_csv(path: Path, columns: int) -> np.ndarray:
    if not path.is_file():
        raise DatasetError(path, "file not found")
    try:
        table = np.loadtxt(path, delimiter=",", comments="#", ndmin=2, dtype=np.float64)
    except ValueError as exc:
        raise DatasetError(path, f"not a numeric CSV ({exc})") from None
    if table.size == 0 or table.shape[1] < columns:
        raise DatasetError(path, f"expected at least {columns} columns and one row")
    return table


def _sensor_yaml(path: Path) -> dict:
    if not path.is_file():
        raise DatasetError(path, "file not found")
    text = path.read_text(encoding="utf-8")
    lines = [line for line in text.splitlines() if not line.startswith("%YAML")]
    try:
        data = yaml.safe_load("\n".join(lines)) or {}
    except yaml.YAMLError as exc:
        raise DatasetError(path, f"not valid YAML ({exc})") from None
    if not isinstance(data, dict):
        raise DatasetError(path, "expected a mapping")
    return data


def _T_BS(path: Path, data: dict) -> np.ndarray:
    try:
        T = np.asarray(data["T_BS"]["data"], dtype=float).reshape(4, 4)
    except KeyError:
        raise DatasetError(path, "missing key 'T_BS: data'") from None
    except (TypeError, ValueError):
        raise DatasetError(path, "'T_BS: data' must hold 16 numbers") from None
    R = T[:3, :3]
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or not np.isfinite(T).all():
        raise DatasetError(path, "'T_BS' is not a rigid transform")
    return T


def _imu(mav0: Path) -> Imu:
    path = mav0 / "imu0" / "data.csv"
    table = _read_csv(path, 7)
    t_ns = table[:, 0].astype(np.int64)
    if np.any(np.diff(t_ns) <= 0):
        raise DatasetError(path, "timestamps must increase")
    noise: dict[str, float] = {}
    yaml_path = mav0 / "imu0" / "sensor.yaml"
    if yaml_path.is_file():
        data = _sensor_yaml(yaml_path)
        for key in (
            "gyroscope_noise_density",
            "gyroscope_random_walk",
            "accelerometer_noise_density",
            "accelerometer_random_walk",
        ):
            if key in data:
                value = data[key]
                if not isinstance(value, int | float) or not value >= 0:
                    raise DatasetError(yaml_path, f"'{key}' must be a number >= 0, got {value!r}")
                noise[key] = float(value)
    return Imu(t_ns, table[:, 1:4].copy(), table[:, 4:7].copy(), noise)


def _asl_groundtruth(mav0: Path) -> tuple[np.ndarray, np.ndarray] | None:
    path = mav0 / "state_groundtruth_estimate0" / "data.csv"
    if not path.is_file():
        return None
    from scipy.spatial.transform import Rotation

    table = _read_csv(path, 8)
    T = np.tile(np.eye(4), (len(table), 1, 1))
    T[:, :3, 3] = table[:, 1:4]
    T[:, :3, :3] = Rotation.from_quat(table[:, [5, 6, 7, 4]]).as_matrix()  # w x y z -> x y z w
    return table[:, 0].astype(np.int64), T


def open_asl(path: Path) -> LidarSequence:
    mav0 = path / "mav0" if (path / "mav0").is_dir() else path
    lidar0 = mav0 / "lidar0"
    index = lidar0 / "data.csv"
    if not index.is_file():
        raise DatasetError(path, "not a LiDAR ASL folder: expected mav0/lidar0/data.csv")
    rows = [
        line.split(",")
        for line in index.read_text(encoding="utf-8").splitlines()
        if line.strip() and not line.startswith("#")
    ]
    try:
        t_ns = np.array([int(r[0]) for r in rows], dtype=np.int64)
    except (ValueError, IndexError):
        raise DatasetError(index, "rows must be '<t_ns>,<file>'") from None
    if len(t_ns) == 0:
        raise DatasetError(index, "lists no scans")
    if np.any(np.diff(t_ns) <= 0):
        raise DatasetError(index, "timestamps must increase")
    scans = [lidar0 / "data" / r[1].strip() for r in rows]
    missing = [p for p in scans if not p.is_file()]
    if missing:
        raise DatasetError(missing[0], f"scan file listed in {index} not found")
    times: list[Path | None] = [lidar0 / "point_time" / p.name for p in scans]
    if not all(t is not None and t.is_file() for t in times):
        times = [None] * len(scans)
    sensor = _sensor_yaml(lidar0 / "sensor.yaml")
    period = sensor.get("scan_period_s", 1.0 / float(sensor.get("rate_hz", 10.0)))
    if not isinstance(period, int | float) or not 0 < period <= 1:
        raise DatasetError(
            lidar0 / "sensor.yaml", f"'scan_period_s' must be in (0, 1], got {period}"
        )
    imu = _imu(mav0) if (mav0 / "imu0" / "data.csv").is_file() else None
    return LidarSequence(
        name=path.name,
        t_ns=t_ns,
        scan_paths=scans,
        time_paths=times,
        T_body_sensor=_T_BS(lidar0 / "sensor.yaml", sensor),
        scan_period_s=float(period),
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
    try:
        times = np.loadtxt(times_path, ndmin=1, dtype=float)
    except ValueError as exc:
        raise DatasetError(times_path, f"not a list of times ({exc})") from None
    if len(times) != len(scans):
        raise DatasetError(times_path, f"{len(times)} times for {len(scans)} scans")
    t_ns = np.round(times * 1e9).astype(np.int64)
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
    data = np.asarray(msg.data, dtype=np.uint8)
    if count == 0 or step <= 0 or data.size < count * step:
        raise DatasetError(where, f"PointCloud2 of {count} points holds {data.size} bytes")
    order = ">" if msg.is_bigendian else "<"
    used = [n for n in ("x", "y", "z", "intensity", "t", "time", "timestamp") if n in fields]
    for name in used:
        if fields[name].datatype not in _POINTFIELD_TYPES:
            raise DatasetError(where, f"PointCloud2 field {name!r}: unknown datatype")
    dtype = np.dtype(
        {
            "names": used,
            "formats": [order + _POINTFIELD_TYPES[fields[n].datatype] for n in used],
            "offsets": [int(fields[n].offset) for n in used],
            "itemsize": step,
        }
    )
    cloud = np.frombuffer(data[: count * step].tobytes(), dtype=dtype, count=count)
    points = np.zeros((count, 4), dtype=np.float32)
    for i, name in enumerate(("x", "y", "z")):
        points[:, i] = cloud[name]
    if "intensity" in used:
        points[:, 3] = cloud["intensity"]
    from slslam.datasets.rosbag import _stamp_ns

    stamp_ns = _stamp_ns(msg)
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
        from slslam.datasets.rosbag import _open_reader, _stamp_ns, read_imu

        path = Path(path)
        self._path = path
        self._reader = _open_reader(path)
        topics = {c.topic: c.msgtype for c in self._reader.connections}
        lidar_topic = self._pick(topics, lidar_topic, POINTCLOUD2_TYPE, required=True)
        imu_topic = self._pick(topics, imu_topic, IMU_TYPE, required=False) if use_imu else None
        self._connections = [c for c in self._reader.connections if c.topic == lidar_topic]
        bag_times, stamps = [], []
        for connection, bag_time, raw in self._reader.messages(connections=self._connections):
            bag_times.append(int(bag_time))
            stamps.append(_stamp_ns(self._reader.deserialize(raw, connection.msgtype)))
        order = np.argsort(np.asarray(stamps, dtype=np.int64), kind="stable")
        self._bag_times = [bag_times[i] for i in order]
        t_ns = np.asarray(stamps, dtype=np.int64)[order]
        if np.any(np.diff(t_ns) <= 0):
            raise DatasetError(path, f"{lidar_topic}: header stamps must increase")
        period = float(np.median(np.diff(t_ns))) * 1e-9 if len(t_ns) > 1 else 0.1
        imu = None
        if imu_topic is not None:
            samples = read_imu(self._reader, imu_topic)
            if len(samples["t_ns"]) < 2 or np.any(np.diff(samples["t_ns"]) <= 0):
                raise DatasetError(path, f"{imu_topic}: needs increasing header stamps")
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
    def _pick(topics: dict[str, str], topic: str | None, msgtype: str, required: bool):
        if topic is not None:
            if topics.get(topic) != msgtype:
                raise DatasetError(
                    topic, f"no {msgtype} topic of that name (topics: {', '.join(sorted(topics))})"
                )
            return topic
        found = sorted(t for t, kind in topics.items() if kind == msgtype)
        if len(found) == 1:
            return found[0]
        if not found and not required:
            return None
        raise DatasetError(
            msgtype,
            f"{'no' if not found else len(found)} topics of this type in the bag "
            f"({', '.join(found) or 'topics: ' + ', '.join(sorted(topics))}): name one",
        )

    def sweep(self, k: int) -> Sweep:
        bag_time = self._bag_times[k]
        for connection, _, raw in self._reader.messages(
            connections=self._connections, start=bag_time, stop=bag_time + 1
        ):
            msg = self._reader.deserialize(raw, connection.msgtype)
            t_ns, points, times = decode_pointcloud2(msg, f"{self._path} ({self.lidar_topic})")
            return Sweep(t_ns, points, times)
        raise DatasetError(self._path, f"sweep {k} of {self.lidar_topic} could not be read back")

    def truncate(self, count: int) -> None:
        super().truncate(count)
        self._bag_times = self._bag_times[:count]


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
