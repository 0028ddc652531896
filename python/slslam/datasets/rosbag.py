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
from typing import Literal

import numpy as np

from slslam.datasets.calibration import (
    CameraCalibration,
    load_yaml,
    numbers_of,
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
        raise DatasetError(path, f"cannot read the bag ({_one_line(exc)})") from None
    except Exception as exc:  # a damaged index or header: rosbags raises many other types
        raise DatasetError(path, f"cannot read the bag ({_one_line(exc)})") from None
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
    fx, fy, cx, cy = numbers_of(need("intrinsics"), 4, f"{name}.intrinsics", path)
    width, height = numbers_of(need("resolution"), 2, f"{name}.resolution", path)
    dist = numbers_of(need("distortion_coeffs"), 4, f"{name}.distortion_coeffs", path)
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
    T = numbers_of(value, 16, key, path).reshape(4, 4)
    if not is_rigid_transform(T):
        raise CalibrationError(path, f"'{key}' is not a rigid transform")
    return T


def load_stereo_calibration(
    paths: Sequence[str | Path],
) -> tuple[CameraCalibration, CameraCalibration]:
    """(left, right) camera calibration from a Kalibr camchain YAML, two EuRoC ``sensor.yaml``
    files (left, right), or a folder with ``cam0/sensor.yaml`` and ``cam1/sensor.yaml`` (an ASL
    ``mav0`` or the folder above it). Errors name the file and the key."""
    calib_paths = [Path(p) for p in paths]
    if len(calib_paths) == 2:
        return (
            CameraCalibration.from_yaml(calib_paths[0]),
            CameraCalibration.from_yaml(calib_paths[1]),
        )
    if len(calib_paths) != 1:
        raise CalibrationError(
            ", ".join(map(str, calib_paths)) or "--calib",
            "give one Kalibr camchain YAML, two EuRoC sensor.yaml files or one ASL folder",
        )
    path = calib_paths[0]
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
            first = next(_messages(reader, [infos[topic]], bag), None)
            if first is None:
                raise DatasetError(where, "the CameraInfo topic holds no message")
            messages.append((where, deserialize(reader, first[2], CAMERA_INFO_TYPE, where)))
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
#: largest image side accepted from a message [px]: far beyond any camera, and it bounds the
#: width * height arithmetic of a garbage header
MAX_IMAGE_SIDE_PX = 1 << 15
#: largest |angular velocity| [rad/s] and |acceleration| [m/s^2] accepted from an Imu message:
#: beyond any IMU's range (tens of rad/s, a few hundred m/s^2), so a larger value is a corrupt one
MAX_GYRO_RADPS = 1e3
MAX_ACC_MPS2 = 1e4


class _Where:
    """Names one message in errors: ``BAG: TOPIC message I (of the topic, from 0)``."""

    def __init__(self, bag: Path, topic: str) -> None:
        self.bag, self.topic = bag, topic

    def __call__(self, index: int) -> str:
        return f"{self.bag}: {self.topic} message {index}"


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())[:160]
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _messages(reader, connections, bag: Path, **window):
    """``reader.messages(...)`` with the reader's own failures (a corrupt chunk or record, bytes
    flipped on disk) as one DatasetError naming the bag."""
    iterator = iter(reader.messages(connections=connections, **window))
    count = 0
    while True:
        try:
            item = next(iterator)
        except StopIteration:
            return
        except Exception as exc:  # rosbags raises many types for a damaged file
            topics = ", ".join(sorted({c.topic for c in connections}))
            raise DatasetError(
                bag, f"cannot read the bag after {count} messages of {topics} ({_one_line(exc)})"
            ) from None
        count += 1
        yield item


def deserialize(reader, raw: bytes, msgtype: str, where: str):
    """One message decoded in a guarded step: a truncated or garbage message is a DatasetError
    naming ``where`` (bag, topic and message index), never the deserializer's own exception."""
    try:
        return reader.deserialize(raw, msgtype)
    except Exception as exc:  # struct.error, IndexError, UnicodeDecodeError, ... from rosbags
        raise DatasetError(
            where, f"{msgtype} message cannot be decoded ({len(raw)} bytes; {_one_line(exc)})"
        ) from None


def _stamp_ns(msg, where: str = "message") -> int:
    """``header.stamp`` [ns]; a stamp with nanoseconds outside [0, 1e9) or before 1970 is a
    DatasetError naming ``where``."""
    try:
        sec, nanosec = int(msg.header.stamp.sec), int(msg.header.stamp.nanosec)
    except (AttributeError, TypeError, ValueError):
        raise DatasetError(where, "message has no header.stamp") from None
    if not 0 <= nanosec < 1_000_000_000 or sec < 0:
        raise DatasetError(where, f"header.stamp {sec} s {nanosec} ns is not a valid time")
    return sec * 1_000_000_000 + nanosec


def imu_topics(path: str | Path) -> list[str]:
    """The bag's ``sensor_msgs/Imu`` topics, sorted."""
    return sorted(t.topic for t in bag_topics(path) if t.msgtype == IMU_TYPE)


def read_imu(reader, topic: str, bag: str | Path = "bag") -> dict[str, np.ndarray]:
    """Every ``sensor_msgs/Imu`` message of ``topic`` in an open reader, sorted by header stamp:
    ``t_ns`` (int64, N), ``gyro`` [rad/s] and ``acc`` [m/s^2] (N, 3). Each message is decoded in
    a guarded step; non-finite or implausible values (beyond MAX_GYRO_RADPS / MAX_ACC_MPS2) and
    header stamps that are all zero or repeat are DatasetErrors naming the bag, topic and message
    index."""
    bag = Path(bag)
    where = _Where(bag, topic)
    connections = [c for c in reader.connections if c.topic == topic]
    rows = []
    for i, (connection, _, raw) in enumerate(_messages(reader, connections, bag)):
        msg = deserialize(reader, raw, connection.msgtype, where(i))
        try:
            w, a = msg.angular_velocity, msg.linear_acceleration
            values = (float(w.x), float(w.y), float(w.z), float(a.x), float(a.y), float(a.z))
        except (AttributeError, TypeError, ValueError):
            raise DatasetError(where(i), "not an Imu message (no angular_velocity)") from None
        rows.append((_stamp_ns(msg, where(i)), *values))
    table = np.array(rows, dtype=np.float64).reshape(-1, 7)
    t_ns = np.array([r[0] for r in rows], dtype=np.int64)
    bad = ~np.isfinite(table[:, 1:]).all(axis=1)
    bad |= np.abs(table[:, 1:4]).max(axis=1, initial=0) > MAX_GYRO_RADPS
    bad |= np.abs(table[:, 4:7]).max(axis=1, initial=0) > MAX_ACC_MPS2
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise DatasetError(
            where(i),
            f"angular velocity or acceleration non-finite or beyond {MAX_GYRO_RADPS:g} rad/s / "
            f"{MAX_ACC_MPS2:g} m/s^2",
        )
    _check_stamps(t_ns, where)
    order = np.argsort(t_ns, kind="stable")
    return {"t_ns": t_ns[order], "gyro": table[order, 1:4], "acc": table[order, 4:7]}


def _check_stamps(t_ns: np.ndarray, where: _Where) -> None:
    """A topic's header stamps, in bag order: not all zero, each later than the one before."""
    if len(t_ns) > 1 and not t_ns.any():
        raise DatasetError(
            f"{where.bag}: {where.topic}", "every header stamp is zero: the messages carry no time"
        )
    back = np.flatnonzero(np.diff(t_ns) <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise DatasetError(
            where(i),
            f"header stamp {int(t_ns[i])} ns is not after message {i - 1}'s ({int(t_ns[i - 1])} "
            "ns): stamps must increase",
        )


def decode_image(msg, msgtype: str, where: str) -> np.ndarray:
    """The pixels of an Image or CompressedImage message: uint8 / uint16, gray or BGR(A).
    Encodings, sizes and the data length are checked; problems are DatasetErrors naming
    ``where``."""
    if msgtype.endswith("CompressedImage"):
        import cv2  # opencv-python-headless

        data = np.frombuffer(bytes(msg.data), np.uint8)
        if data.size == 0:
            raise DatasetError(where, "CompressedImage with no bytes")
        try:
            image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED)
        except cv2.error:
            image = None
        if image is None or image.size == 0:
            raise DatasetError(
                where,
                f"cannot decode the compressed image ({data.size} bytes, format "
                f"{str(msg.format)[:40]!r})",
            )
        return image
    encoding = str(msg.encoding).lower()
    if encoding not in ENCODINGS:
        raise DatasetError(
            where,
            f"image encoding {str(msg.encoding)[:40]!r} is not supported ({', '.join(ENCODINGS)})",
        )
    dtype, channels, reversed_order = ENCODINGS[encoding]
    width, height, step = int(msg.width), int(msg.height), int(msg.step)
    if not (0 < width <= MAX_IMAGE_SIDE_PX and 0 < height <= MAX_IMAGE_SIDE_PX):
        raise DatasetError(
            where, f"image size {width}x{height} outside 1..{MAX_IMAGE_SIDE_PX} pixels a side"
        )
    row_bytes = width * channels * np.dtype(dtype).itemsize
    data = np.frombuffer(bytes(msg.data), np.uint8)
    if step < row_bytes or step > row_bytes + 4096 or data.size != step * height:
        raise DatasetError(
            where,
            f"image data ({data.size} bytes, step {step}) does not match {width}x{height} "
            f"{encoding} ({height} rows of at least {row_bytes} bytes)",
        )
    rows = data.reshape(height, step)[:, :row_bytes]
    order: Literal[">", "<"] = ">" if msg.is_bigendian else "<"
    pixels = np.ascontiguousarray(rows).view(np.dtype(dtype).newbyteorder(order))
    pixels = pixels.astype(dtype, copy=False).reshape(height, width, channels)
    if reversed_order:
        pixels = pixels[:, :, [2, 1, 0, 3][:channels]]
    return pixels[:, :, 0] if channels == 1 else pixels


@dataclass(frozen=True)
class _Message:
    """Where one image message lies in the bag: topic, index in the topic, receive time and
    header stamp [ns]."""

    topic: str
    index: int
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
        if left_topic == right_topic:
            raise DatasetError(
                self.path,
                f"the left and right camera topics are both {left_topic!r}: give two topics",
            )
        if not (isinstance(stereo_tolerance_ns, int) and 0 <= stereo_tolerance_ns <= 10**9):
            raise DatasetError(self.path, "stereo_tolerance_ns must be an integer in [0, 1e9]")
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
        if imu_topic is not None and imu_topic in (left_topic, right_topic):
            raise DatasetError(self.path, f"--imu {imu_topic!r} is also a camera topic")
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
        wheres = {topic: _Where(self.path, topic) for topic in stamps}
        connections = [c for c in reader.connections if c.topic in stamps]
        for connection, bag_time, raw in _messages(reader, connections, self.path):
            topic = connection.topic
            where = wheres[topic](len(stamps[topic]))
            msg = deserialize(reader, raw, connection.msgtype, where)
            stamp = _stamp_ns(msg, where)
            index = len(stamps[topic])
            stamps[topic].append((stamp, _Message(topic, index, int(bag_time), stamp)))
        for topic, items in stamps.items():
            _check_stamps(np.array([t for t, _ in items], dtype=np.int64), wheres[topic])
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
        where = (
            f"{self.path}: {which} image, {message.topic} message {message.index} "
            f"(t = {message.stamp_ns} ns)"
        )
        connections = [c for c in reader.connections if c.topic == message.topic]
        for connection, _, raw in _messages(
            reader,
            connections,
            self.path,
            start=message.bag_time_ns,
            stop=message.bag_time_ns + 1,
        ):
            msg = deserialize(reader, raw, connection.msgtype, where)
            if _stamp_ns(msg, where) != message.stamp_ns:
                continue
            try:
                image = self._gray.convert(decode_image(msg, connection.msgtype, where), where)
            except ValueError as exc:
                if isinstance(exc, DatasetError):
                    raise
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

    @property
    def has_imu(self) -> bool:
        """False when no IMU topic was chosen: the run is camera-only."""
        return self.imu_topic is not None

    def imu(self) -> dict[str, np.ndarray]:
        """IMU samples of ``imu_topic``: ``t_ns`` (int64, N), ``gyro`` [rad/s], ``acc`` [m/s^2]."""
        if self.imu_topic is None:
            raise DatasetError(self.path, "no IMU topic given")
        return read_imu(self._reader(), self.imu_topic, self.path)

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
