"""Stereo sequences from ROS bags, read without ROS (``rosbags``).

A ROS1 ``.bag`` file, or a ROS2 bag (the folder with ``metadata.yaml`` and its ``.db3`` SQLite or
``.mcap`` file, or that file itself), with the two cameras as ``sensor_msgs/Image`` (mono8,
mono16, bgr8, rgb8, bgra8, rgba8 and their 8UC/16UC names) or ``sensor_msgs/CompressedImage``
(PNG, JPEG: whatever OpenCV decodes) and optionally ``sensor_msgs/Imu``.

Stereo pairs are matched by the messages' ``header.stamp`` (exactly, or within
``stereo_tolerance_ns``); a left image without a right one is dropped with one warning. The
calibration comes from YAML (:func:`load_stereo_calibration`): a Kalibr camchain (``cam0``,
``cam1`` with ``T_cn_cnm1``), or EuRoC ``sensor.yaml`` files (two files, or a folder holding
``cam0/sensor.yaml`` and ``cam1/sensor.yaml``); without YAML, from the bag's
``sensor_msgs/CameraInfo`` next to each image topic (``<namespace>/camera_info``, plumb_bob,
the stereo extrinsics from ``R`` and the right camera's ``P``: :func:`camera_info_calibration`).
Images are converted to 8-bit gray as :class:`~slslam.datasets.images.GrayImageReader` does and
rectified as :class:`EurocSequence` rectifies, so a bag and the ASL folder it was made from give
the tracker the same pixels.

:class:`RosbagSequence` offers what :class:`EurocSequence` offers the tracker (``camera``,
``len``, ``sequence[i]`` -> :class:`StereoFrame`, ``timestamps_ns``, ``imu()``); a bag has no
ground truth (``groundtruth_path`` is None: give ``slslam run --groundtruth FILE``).
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from slslam.datasets.calibration import (
    CameraCalibration,
    _numbers,
    load_yaml,
)
from slslam.datasets.euroc import (
    RectifiedStereoCamera,
    StereoFrame,
    rectified_camera,
    stereo_rectifier,
)
from slslam.datasets.images import GrayImageReader
from slslam.errors import CalibrationError, DatasetError
from slslam.geometry import invert_transform, is_rigid_transform

log = logging.getLogger(__name__)

IMAGE_TYPES = ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage")
IMU_TYPE = "sensor_msgs/msg/Imu"
CAMERA_INFO_TYPE = "sensor_msgs/msg/CameraInfo"
MAX_K3 = 1e-9  # plumb_bob's k3 must vanish: the rectifier models k1 k2 p1 p2 only
#: encoding -> (dtype, channels, channel order reversed from OpenCV's BGR)
ENCODINGS = {
    "mono8": (np.uint8, 1, False),
    "8uc1": (np.uint8, 1, False),
    "mono16": (np.uint16, 1, False),
    "16uc1": (np.uint16, 1, False),
    "bgr8": (np.uint8, 3, False),
    "8uc3": (np.uint8, 3, False),
    "rgb8": (np.uint8, 3, True),
    "bgra8": (np.uint8, 4, False),
    "8uc4": (np.uint8, 4, False),
    "rgba8": (np.uint8, 4, True),
    "bgr16": (np.uint16, 3, False),
    "rgb16": (np.uint16, 3, True),
}


@dataclass(frozen=True)
class TopicInfo:
    """One topic of a bag: name, message type (ROS2 spelling) and number of messages."""

    topic: str
    msgtype: str
    count: int


# -- finding and opening bags -------------------------------------------------------------------
def _bag_paths(path: Path) -> list[Path]:
    """What ``AnyReader`` opens: the ROS1 file, or the ROS2 bag folder."""
    if path.is_file() and path.suffix == ".bag":
        return [path]
    if path.is_dir() and (path / "metadata.yaml").is_file():
        return [path]
    if path.is_file() and path.suffix in (".db3", ".mcap"):
        if (path.parent / "metadata.yaml").is_file():
            return [path.parent]
        raise DatasetError(
            path, "a ROS2 storage file needs its bag folder's metadata.yaml next to it"
        )
    raise DatasetError(
        path, "not a ROS bag: expected a ROS1 .bag file or a ROS2 bag folder (metadata.yaml)"
    )


def is_rosbag(path: str | Path) -> bool:
    """True when ``path`` is a ROS1 ``.bag`` file, a ROS2 bag folder or its storage file."""
    try:
        _bag_paths(Path(path))
    except DatasetError:
        return False
    return True


def _open_reader(path: Path):
    from rosbags.highlevel import AnyReader, AnyReaderError

    paths = _bag_paths(path)  # not a bag: its own message
    try:
        reader = AnyReader(paths)
        reader.open()
    except (AnyReaderError, OSError, ValueError, KeyError) as exc:
        raise DatasetError(path, f"cannot read the bag ({exc})") from None
    return reader


def bag_topics(path: str | Path) -> list[TopicInfo]:
    """Every topic of the bag with its message type and count, sorted by name."""
    path = Path(path)
    reader = _open_reader(path)
    try:
        counts: dict[str, int] = {}
        types: dict[str, str] = {}
        for connection in reader.connections:
            counts[connection.topic] = counts.get(connection.topic, 0) + connection.msgcount
            types[connection.topic] = connection.msgtype
        return [TopicInfo(t, types[t], counts[t]) for t in sorted(counts)]
    finally:
        reader.close()


# -- calibration ----------------------------------------------------------------------------------
def _kalibr_camera(data: dict, name: str, path: Path, T_body_cam: np.ndarray) -> CameraCalibration:
    entry = data.get(name)
    if not isinstance(entry, dict):
        raise CalibrationError(path, f"missing key '{name}' (a Kalibr camchain has cam0 and cam1)")

    def need(key: str):
        if key not in entry:
            raise CalibrationError(path, f"missing key '{name}.{key}'")
        return entry[key]

    if need("camera_model") != "pinhole":
        raise CalibrationError(
            path, f"'{name}.camera_model' {entry['camera_model']!r} is not supported (pinhole)"
        )
    if need("distortion_model") not in ("radtan", "radial-tangential"):
        raise CalibrationError(
            path,
            f"'{name}.distortion_model' {entry['distortion_model']!r} is not supported (radtan)",
        )
    fx, fy, cx, cy = _numbers(need("intrinsics"), 4, f"{name}.intrinsics", path)
    width, height = _numbers(need("resolution"), 2, f"{name}.resolution", path)
    dist = _numbers(need("distortion_coeffs"), 4, f"{name}.distortion_coeffs", path)
    if fx <= 0 or fy <= 0 or width <= 0 or height <= 0 or width != int(width):
        raise CalibrationError(path, f"'{name}': focal lengths and resolution must be positive")
    return CameraCalibration(
        path=path,
        T_body_cam=T_body_cam,
        width=int(width),
        height=int(height),
        fx=float(fx),
        fy=float(fy),
        cx=float(cx),
        cy=float(cy),
        distortion=tuple(float(d) for d in dist),  # type: ignore[arg-type]
    )


def _transform(value, key: str, path: Path) -> np.ndarray:
    T = _numbers(value, 16, key, path).reshape(4, 4)
    if not is_rigid_transform(T):
        raise CalibrationError(path, f"'{key}' is not a rigid transform")
    return T


def load_stereo_calibration(
    paths: Sequence[str | Path],
) -> tuple[CameraCalibration, CameraCalibration]:
    """(left, right) camera calibration from a Kalibr camchain YAML, two EuRoC ``sensor.yaml``
    files (left, right), or a folder with ``cam0/sensor.yaml`` and ``cam1/sensor.yaml`` (an ASL
    ``mav0`` or the folder above it). Errors name the file and the key."""
    paths = [Path(p) for p in paths]
    if len(paths) == 2:
        return CameraCalibration.from_yaml(paths[0]), CameraCalibration.from_yaml(paths[1])
    if len(paths) != 1:
        raise CalibrationError(
            ", ".join(map(str, paths)) or "--calib",
            "give one Kalibr camchain YAML, two EuRoC sensor.yaml files or one ASL folder",
        )
    path = paths[0]
    if path.is_dir():
        for root in (path / "mav0", path):
            if (root / "cam0" / "sensor.yaml").is_file():
                return load_stereo_calibration(
                    [root / "cam0" / "sensor.yaml", root / "cam1" / "sensor.yaml"]
                )
        raise CalibrationError(path, "no cam0/sensor.yaml in this folder")
    data = load_yaml(path)
    if "cam0" not in data and "T_BS" in data:
        raise CalibrationError(
            path, "a EuRoC sensor.yaml holds one camera: give --calib twice (left, then right)"
        )
    T_body_cam0 = np.eye(4)  # the body is cam0 unless the camchain places the IMU
    cam0 = data.get("cam0")
    if isinstance(cam0, dict) and "T_cam_imu" in cam0:
        T_body_cam0 = invert_transform(_transform(cam0["T_cam_imu"], "cam0.T_cam_imu", path))
    cam1 = data.get("cam1")
    if not isinstance(cam1, dict) or "T_cn_cnm1" not in cam1:
        raise CalibrationError(path, "missing key 'cam1.T_cn_cnm1' (pose of cam0 in cam1)")
    T_cam1_cam0 = _transform(cam1["T_cn_cnm1"], "cam1.T_cn_cnm1", path)
    left = _kalibr_camera(data, "cam0", path, T_body_cam0)
    right = _kalibr_camera(data, "cam1", path, T_body_cam0 @ invert_transform(T_cam1_cam0))
    return left, right


def kalibr_topics(path: str | Path) -> tuple[str | None, str | None]:
    """The ``rostopic`` of cam0 and cam1 in a Kalibr camchain (None where absent)."""
    path = Path(path)
    if path.is_dir():
        return None, None
    data = load_yaml(path)
    topics = []
    for name in ("cam0", "cam1"):
        entry = data.get(name)
        topic = entry.get("rostopic") if isinstance(entry, dict) else None
        topics.append(topic if isinstance(topic, str) else None)
    return topics[0], topics[1]


def _info_field(msg, name: str, count: int, where: str) -> np.ndarray:
    """A CameraInfo array (ROS1 spells them D K R P, ROS2 d k r p)."""
    value = getattr(msg, name.lower(), None)
    value = getattr(msg, name.upper(), None) if value is None else value
    array = np.asarray(value, dtype=np.float64).reshape(-1)
    if array.size != count or not np.all(np.isfinite(array)):
        raise CalibrationError(where, f"'{name}' must hold {count} finite numbers")
    return array


def _distortion(msg, where: str) -> np.ndarray:
    """plumb_bob k1 k2 p1 p2 (k3 must be 0; an empty D means no distortion)."""
    raw = getattr(msg, "d", None)
    raw = getattr(msg, "D", None) if raw is None else raw
    D = np.zeros(5) if raw is None or len(raw) == 0 else _info_field(msg, "D", 5, where)
    if abs(D[4]) > MAX_K3:
        raise CalibrationError(where, f"'D' has k3 = {D[4]:g}: only k1 k2 p1 p2 are modelled")
    return D[:4]


def camera_info_calibration(
    bag: str | Path, left_topic: str, right_topic: str
) -> tuple[CameraCalibration, CameraCalibration]:
    """(left, right) calibration from the bag's ``CameraInfo`` beside each image topic.

    Intrinsics and plumb_bob distortion from ``K`` and ``D`` (k3 must be 0); the stereo
    extrinsics from the rectification rotations ``R`` (rectified <- camera) and the right
    camera's ``P[0, 3] = -fx * baseline``: ``T_right_left = (R_right^T R_left, -R_right^T
    [baseline, 0, 0])``. The body frame is the left camera. Errors name the bag and topic."""
    bag = Path(bag)
    reader = _open_reader(bag)
    try:
        infos = {c.topic: c for c in reader.connections if c.msgtype == CAMERA_INFO_TYPE}
        messages = []
        for image_topic in (left_topic, right_topic):
            topic = image_topic.rsplit("/", 1)[0] + "/camera_info"
            where = f"{bag}:{topic}"
            if topic not in infos:
                raise DatasetError(
                    bag,
                    f"no {CAMERA_INFO_TYPE} {topic!r} beside {image_topic!r}: give the "
                    "calibration as YAML (--calib)",
                )
            _, _, raw = next(iter(reader.messages(connections=[infos[topic]])))
            messages.append((where, reader.deserialize(raw, CAMERA_INFO_TYPE)))
    finally:
        reader.close()
    cameras = []
    for where, msg in messages:
        if msg.distortion_model not in ("plumb_bob", "radtan", ""):
            raise CalibrationError(
                where, f"distortion_model {msg.distortion_model!r} is not supported (plumb_bob)"
            )
        K = _info_field(msg, "K", 9, where).reshape(3, 3)
        D = _distortion(msg, where)
        cameras.append(
            (
                where,
                K,
                D,
                _info_field(msg, "R", 9, where).reshape(3, 3),
                _info_field(msg, "P", 12, where).reshape(3, 4),
                msg,
            )
        )
    (_, _, _, R_left, _, _), (where_right, _, _, R_right, P_right, _) = cameras
    baseline_m = -P_right[0, 3] / P_right[0, 0] if P_right[0, 0] > 0 else 0.0
    if baseline_m <= 0:
        raise CalibrationError(
            where_right,
            "'P'[0, 3] gives no stereo baseline (-fx * baseline expected): give --calib",
        )
    T_right_left = np.eye(4)
    T_right_left[:3, :3] = R_right.T @ R_left
    T_right_left[:3, 3] = -R_right.T @ np.array([baseline_m, 0.0, 0.0])
    poses = (np.eye(4), invert_transform(T_right_left))
    result = []
    for (where, K, D, _, _, msg), T_body_cam in zip(cameras, poses, strict=True):
        if K[0, 0] <= 0 or K[1, 1] <= 0 or int(msg.width) <= 0 or int(msg.height) <= 0:
            raise CalibrationError(where, "'K' focal lengths and the image size must be positive")
        result.append(
            CameraCalibration(
                path=Path(where),
                T_body_cam=T_body_cam,
                width=int(msg.width),
                height=int(msg.height),
                fx=float(K[0, 0]),
                fy=float(K[1, 1]),
                cx=float(K[0, 2]),
                cy=float(K[1, 2]),
                distortion=tuple(float(d) for d in D),  # type: ignore[arg-type]
            )
        )
    return result[0], result[1]


# -- messages ---------------------------------------------------------------------------------
def _stamp_ns(msg) -> int:
    return int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)


def read_imu(reader, topic: str) -> dict[str, np.ndarray]:
    """Every ``sensor_msgs/Imu`` message of ``topic`` in an open reader, sorted by header stamp:
    ``t_ns`` (int64, N), ``gyro`` [rad/s] and ``acc`` [m/s^2] (N, 3)."""
    connections = [c for c in reader.connections if c.topic == topic]
    rows = []
    for connection, _, raw in reader.messages(connections=connections):
        msg = reader.deserialize(raw, connection.msgtype)
        w, a = msg.angular_velocity, msg.linear_acceleration
        rows.append((_stamp_ns(msg), w.x, w.y, w.z, a.x, a.y, a.z))
    rows.sort(key=lambda r: r[0])
    table = np.array([r[1:] for r in rows], dtype=np.float64).reshape(-1, 6)
    return {
        "t_ns": np.array([r[0] for r in rows], dtype=np.int64),
        "gyro": table[:, :3],
        "acc": table[:, 3:],
    }


def decode_image(msg, msgtype: str, where: str) -> np.ndarray:
    """The pixels of an Image or CompressedImage message: uint8 / uint16, gray or BGR(A)."""
    if msgtype.endswith("CompressedImage"):
        import cv2  # opencv-python-headless

        image = cv2.imdecode(np.frombuffer(msg.data, np.uint8), cv2.IMREAD_UNCHANGED)
        if image is None:
            raise DatasetError(where, f"cannot decode the compressed image (format {msg.format!r})")
        return image
    encoding = msg.encoding.lower()
    if encoding not in ENCODINGS:
        raise DatasetError(
            where, f"image encoding {msg.encoding!r} is not supported ({', '.join(ENCODINGS)})"
        )
    dtype, channels, reversed_order = ENCODINGS[encoding]
    width, height, step = int(msg.width), int(msg.height), int(msg.step)
    row_bytes = width * channels * np.dtype(dtype).itemsize
    data = np.frombuffer(msg.data, np.uint8)
    if step < row_bytes or data.size < step * height:
        raise DatasetError(
            where, f"image data ({data.size} bytes, step {step}) too short for {width}x{height}"
        )
    rows = data[: step * height].reshape(height, step)[:, :row_bytes]
    order = ">" if msg.is_bigendian else "<"
    pixels = np.ascontiguousarray(rows).view(np.dtype(dtype).newbyteorder(order))
    pixels = pixels.astype(dtype, copy=False).reshape(height, width, channels)
    if reversed_order:
        pixels = pixels[:, :, [2, 1, 0, 3][:channels]]
    return pixels[:, :, 0] if channels == 1 else pixels


@dataclass(frozen=True)
class _Message:
    """Where one image message lies in the bag: topic, receive time and header stamp [ns]."""

    topic: str
    bag_time_ns: int
    stamp_ns: int


class RosbagSequence:
    """A stereo sequence in a ROS bag, read lazily in time order (see the module docstring).

    Args:
        path: ROS1 ``.bag`` file, or ROS2 bag folder (or its ``.db3`` / ``.mcap`` file).
        left_topic, right_topic: the two cameras' image topics.
        calibration: path(s) for :func:`load_stereo_calibration`; None: the bag's CameraInfo
            (:func:`camera_info_calibration`).
        imu_topic: an ``Imu`` topic for :meth:`imu` (optional).
        stereo_tolerance_ns: largest header-stamp difference accepted as one pair.
        rectify: return rectified images (default) or the raw distorted ones.
    """

    def __init__(
        self,
        path: str | Path,
        left_topic: str,
        right_topic: str,
        calibration: Sequence[str | Path] | None,
        imu_topic: str | None = None,
        stereo_tolerance_ns: int = 0,
        rectify: bool = True,
    ) -> None:
        self.path = Path(path)
        self.rectify = rectify
        self.imu_topic = imu_topic
        self._local = threading.local()
        reader = self._reader()
        self._topics = {c.topic: c.msgtype for c in reader.connections}
        for flag, topic in (("left", left_topic), ("right", right_topic)):
            if topic not in self._topics:
                raise DatasetError(
                    self.path,
                    f"no topic {topic!r} for the {flag} camera (topics: "
                    f"{', '.join(sorted(self._topics)) or 'none'})",
                )
            if self._topics[topic] not in IMAGE_TYPES:
                raise DatasetError(
                    self.path,
                    f"topic {topic!r} holds {self._topics[topic]}, not {' or '.join(IMAGE_TYPES)}",
                )
        if imu_topic is not None and self._topics.get(imu_topic) != IMU_TYPE:
            raise DatasetError(
                self.path, f"no {IMU_TYPE} topic {imu_topic!r} ({', '.join(sorted(self._topics))})"
            )
        self.left_topic, self.right_topic = left_topic, right_topic
        self.left_calibration, self.right_calibration = (
            load_stereo_calibration(calibration)
            if calibration
            else camera_info_calibration(self.path, left_topic, right_topic)
        )
        self._pairs, self.timestamps_ns = self._index(reader, stereo_tolerance_ns)
        self._gray = GrayImageReader()
        self._rectifier = stereo_rectifier(self.left_calibration, self.right_calibration, path)

    # -- reading ------------------------------------------------------------------------------
    def _reader(self):
        """One open reader per thread (the tracker's pipeline reads on its own thread)."""
        reader = getattr(self._local, "reader", None)
        if reader is None:
            reader = self._local.reader = _open_reader(self.path)
        return reader

    def _index(self, reader, tolerance_ns: int):
        stamps: dict[str, list[tuple[int, _Message]]] = {self.left_topic: [], self.right_topic: []}
        connections = [c for c in reader.connections if c.topic in stamps]
        for connection, bag_time, raw in reader.messages(connections=connections):
            msg = reader.deserialize(raw, connection.msgtype)
            stamp = _stamp_ns(msg)
            stamps[connection.topic].append((stamp, _Message(connection.topic, bag_time, stamp)))
        left = sorted(stamps[self.left_topic], key=lambda item: item[0])
        right = sorted(stamps[self.right_topic], key=lambda item: item[0])
        if not left or not right:
            raise DatasetError(self.path, "no images on the left or the right camera topic")
        right_t = np.array([t for t, _ in right], dtype=np.int64)
        pairs: list[tuple[_Message, _Message]] = []
        times: list[int] = []
        for t, message in left:
            j = int(np.clip(np.searchsorted(right_t, t), 0, len(right_t) - 1))
            candidates = [k for k in (j - 1, j) if 0 <= k < len(right_t)]
            k = min(candidates, key=lambda c: abs(int(right_t[c]) - t))
            if abs(int(right_t[k]) - t) <= tolerance_ns and (not times or t > times[-1]):
                pairs.append((message, right[k][1]))
                times.append(t)
        if len(pairs) < len(left):
            log.warning(
                "%s: %d of %d left images have no right image within %d ns and are skipped",
                self.path,
                len(left) - len(pairs),
                len(left),
                tolerance_ns,
            )
        if not pairs:
            raise DatasetError(
                self.path,
                f"no stereo pairs: {self.left_topic} and {self.right_topic} share no header "
                f"stamps within {tolerance_ns} ns",
            )
        return pairs, np.asarray(times, dtype=np.int64)

    def _image(self, message: _Message, which: str) -> np.ndarray:
        reader = self._reader()
        where = f"{self.path}: {which} image {message.topic} at t = {message.stamp_ns} ns"
        connections = [c for c in reader.connections if c.topic == message.topic]
        for connection, _, raw in reader.messages(
            connections=connections, start=message.bag_time_ns, stop=message.bag_time_ns + 1
        ):
            msg = reader.deserialize(raw, connection.msgtype)
            if _stamp_ns(msg) != message.stamp_ns:
                continue
            try:
                image = self._gray.convert(decode_image(msg, connection.msgtype, where), where)
            except ValueError as exc:
                raise DatasetError(where, str(exc)) from None
            expected = (self.left_calibration.height, self.left_calibration.width)
            if image.shape != expected:
                raise DatasetError(
                    where,
                    f"image is {image.shape[1]}x{image.shape[0]} but the calibration is for "
                    f"{expected[1]}x{expected[0]}",
                )
            return image
        raise DatasetError(where, "message not found again in the bag")

    # -- the sequence interface -----------------------------------------------------------
    @property
    def camera(self) -> RectifiedStereoCamera:
        """The rectified stereo camera the tracker sees."""
        return rectified_camera(self._rectifier, self.left_calibration)

    @property
    def groundtruth_path(self) -> None:
        """Bags carry no ground truth here (use ``--groundtruth FILE``)."""
        return None

    def __len__(self) -> int:
        return len(self._pairs)

    def __getitem__(self, index: int) -> StereoFrame:
        if not -len(self) <= index < len(self):
            raise IndexError(f"frame {index} out of range (sequence has {len(self)})")
        index %= len(self)
        left_msg, right_msg = self._pairs[index]
        t_ns = int(self.timestamps_ns[index])
        left = self._image(left_msg, "left")
        right = self._image(right_msg, "right")
        if self.rectify:
            left, right = self._rectifier.rectify(left, right)
        return StereoFrame(index=index, t_ns=t_ns, left=left, right=right)

    def __iter__(self) -> Iterator[StereoFrame]:
        for i in range(len(self)):
            yield self[i]

    def __str__(self) -> str:
        return str(self.path)

    def imu(self) -> dict[str, np.ndarray]:
        """IMU samples of ``imu_topic``: ``t_ns`` (int64, N), ``gyro`` [rad/s], ``acc`` [m/s^2]."""
        if self.imu_topic is None:
            raise DatasetError(self.path, "no IMU topic given")
        return read_imu(self._reader(), self.imu_topic)

    def close(self) -> None:
        """Closes this thread's reader."""
        reader = getattr(self._local, "reader", None)
        if reader is not None:
            reader.close()
            self._local.reader = None

    def __enter__(self) -> RosbagSequence:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
