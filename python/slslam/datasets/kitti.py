"""KITTI stereo sequences in the two layouts KITTI ships them in.

Odometry (``data_odometry_gray`` / ``_color``; poses from ``data_odometry_poses``)::

    <root>/sequences/NN/image_0/000000.png ...   left camera (image_2/ for the colour pair)
    <root>/sequences/NN/image_1/000000.png ...   right camera (image_3/)
    <root>/sequences/NN/calib.txt                P0 ... P3 (3 x 4 rectified projections)
    <root>/sequences/NN/times.txt                seconds since the first frame, one a line
    <root>/poses/NN.txt                          ground truth T_world_cam0 (optional, 00-10)

Raw (a ``<date>_drive_<NNNN>_sync`` folder; its calibration sits beside it in ``<date>/``)::

    <drive>/image_00/data/0000000000.png ...     left camera, rectified (image_02/ colour)
    <drive>/image_00/timestamps.txt              wall-clock time a line (UTC)
    <drive>/image_01/...                         right camera (image_03/)
    <drive>/calib_cam_to_cam.txt or <drive>/../calib_cam_to_cam.txt
                                                 P_rect_00, P_rect_01, S_rect_00 ...

Both layouts hold images rectified already: the rectified left camera is the frame the tracker
estimates, and the body frame is that camera (``T_body_cam`` is the identity). Intrinsics come
from the left projection, the baseline from the two projections' ``P[0, 3] = -fx * x_cam``
terms. Raw timestamps become Unix nanoseconds (UTC), odometry ones nanoseconds since the first
frame. The raw ``_extract`` download (unrectified, distorted images) is refused with the reason.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from evo.core.trajectory import PoseTrajectory3D

from slslam.datasets.calibration import numbers_of, require_key
from slslam.datasets.euroc import (
    MIN_BASELINE_M,
    RectifiedStereoCamera,
    StereoFrame,
    read_sequence_image,
)
from slslam.datasets.images import GrayImageReader
from slslam.datasets.trajectory_io import read_trajectory
from slslam.errors import CalibrationError, DatasetError
from slslam.yaml_io import short_repr

KittiLayout = Literal["odometry", "raw"]

#: Largest difference between a raw drive's left and right timestamps of one pair [ns]. KITTI's
#: cameras are triggered together; their logged stamps differ by up to a few milliseconds.
RAW_STEREO_TOLERANCE_NS = 20_000_000
#: Relative difference allowed between the two rectified projections' fx, fy, cx, cy: a pair
#: whose projections differ more is not one rectified stereo pair.
RECTIFIED_INTRINSICS_RTOL = 1e-6

# (layout, left folder, right folder, left projection key, right projection key)
_ODOMETRY_PAIRS = (("image_0", "image_1", "P0", "P1"), ("image_2", "image_3", "P2", "P3"))
_RAW_PAIRS = (
    ("image_00", "image_01", "P_rect_00", "P_rect_01"),
    ("image_02", "image_03", "P_rect_02", "P_rect_03"),
)
_RAW_CALIB = "calib_cam_to_cam.txt"
_RAW_STAMP = re.compile(r"^\d{4}-\d{2}-\d{2} \d{2}:\d{2}:\d{2}(\.\d{1,9})?$")


def read_kitti_calibration(path: str | Path) -> dict[str, str]:
    """The ``KEY: values`` lines of a KITTI calibration file (values as text, read on demand)."""
    path = Path(path)
    if not path.is_file():
        raise CalibrationError(path, "calibration file not found")
    entries: dict[str, str] = {}
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise CalibrationError(
            path, "not a text file (KITTI calibration is 'KEY: values')"
        ) from None
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        key, sep, value = line.partition(":")
        if not sep or not key.strip() or " " in key.strip():
            raise CalibrationError(
                path, f"line {number}: expected 'KEY: values', got {short_repr(line, 60)}"
            )
        if key.strip() in entries:
            raise CalibrationError(path, f"line {number}: key '{key.strip()}' given twice")
        entries[key.strip()] = value.strip()
    return entries


def _numbers(entries: dict[str, str], key: str, count: int, path: Path) -> np.ndarray:
    """The ``count`` numbers of calibration line ``key``."""
    return numbers_of(require_key(entries, key, path).split(), count, key, path)


def stereo_camera_from_projections(
    entries: dict[str, str], left_key: str, right_key: str, path: Path, width: int, height: int
) -> RectifiedStereoCamera:
    """The rectified pair given by two 3 x 4 projections ``P = K [I | -c]`` of one calibration
    file (``c``: the camera centre in the rectified reference camera, along x)."""
    P_left = _numbers(entries, left_key, 12, path).reshape(3, 4)
    P_right = _numbers(entries, right_key, 12, path).reshape(3, 4)
    for key, P in ((left_key, P_left), (right_key, P_right)):
        K = P[:, :3]
        if K[0, 0] <= 0 or K[1, 1] <= 0 or K[2, 2] != 1.0 or K[0, 1] != 0.0 or K[1, 0] != 0.0:
            raise CalibrationError(
                path,
                f"'{key}': not a rectified projection (expected fx > 0, fy > 0, no skew and a "
                f"last row 0 0 1 0; got {short_repr(P.ravel().tolist(), 80)})",
            )
        if P[1, 3] != 0.0 or P[2, 3] != 0.0:
            raise CalibrationError(
                path,
                f"'{key}': the camera is offset in y or z (P[1,3] = {P[1, 3]:g}, P[2,3] = "
                f"{P[2, 3]:g}); only a horizontal stereo pair is read",
            )
    if not np.allclose(P_left[:, :3], P_right[:, :3], rtol=RECTIFIED_INTRINSICS_RTOL, atol=0):
        raise CalibrationError(
            path,
            f"'{left_key}' and '{right_key}' have different intrinsics: the pair is not "
            "rectified together",
        )
    fx = P_left[0, 0]
    x_left, x_right = -P_left[0, 3] / fx, -P_right[0, 3] / fx
    baseline_m = x_right - x_left
    if baseline_m < MIN_BASELINE_M:
        raise CalibrationError(
            path,
            f"'{right_key}' puts the right camera {baseline_m:.4g} m along x from the left one: "
            f"a stereo pair needs it to the right, by at least {MIN_BASELINE_M * 1000:g} mm",
        )
    return RectifiedStereoCamera(
        fx=float(fx),
        fy=float(P_left[1, 1]),
        cx=float(P_left[0, 2]),
        cy=float(P_left[1, 2]),
        width=width,
        height=height,
        baseline_m=float(baseline_m),
        T_body_cam=np.eye(4),
    )


def _images(folder: Path) -> list[Path]:
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() == ".png")
    if not files:
        raise DatasetError(folder, "no PNG images in this folder")
    return files


def _odometry_times(path: Path, count: int) -> np.ndarray:
    if not path.is_file():
        raise DatasetError(path, "missing times file (seconds since the first frame, one a line)")
    try:
        seconds = np.loadtxt(path, ndmin=1, dtype=np.float64)
    except ValueError as exc:
        raise DatasetError(path, f"not a times file ({short_repr(str(exc), 100)})") from None
    if seconds.ndim != 1:
        raise DatasetError(path, "expected one time [s] a line")
    return _checked_stamps(path, np.round(seconds * 1e9), count)


def _raw_times(path: Path, count: int) -> np.ndarray:
    if not path.is_file():
        raise DatasetError(path, "missing timestamps file (one 'YYYY-MM-DD hh:mm:ss.fff' a line)")
    lines = [
        line.strip() for line in path.read_text(encoding="utf-8", errors="replace").split("\n")
    ]
    lines = [line for line in lines if line]
    for number, line in enumerate(lines, start=1):
        if not _RAW_STAMP.match(line):
            raise DatasetError(
                path, f"line {number}: {short_repr(line, 40)} is not 'YYYY-MM-DD hh:mm:ss.fff'"
            )
    try:
        stamps = np.array([line.replace(" ", "T") for line in lines], dtype="datetime64[ns]")
    except ValueError as exc:
        raise DatasetError(path, f"invalid date ({short_repr(str(exc), 80)})") from None
    if np.any(np.isnat(stamps)):
        raise DatasetError(path, "a timestamp is not a date ('NaT')")
    return _checked_stamps(path, stamps.astype(np.int64), count)


def _checked_stamps(path: Path, stamps_ns: np.ndarray, count: int) -> np.ndarray:
    if stamps_ns.shape[0] != count:
        raise DatasetError(
            path, f"has {stamps_ns.shape[0]} timestamps for {count} images in the image folder"
        )
    if stamps_ns.dtype.kind == "f" and (
        not np.all(np.isfinite(stamps_ns)) or np.any(np.abs(stamps_ns) >= 2.0**63)
    ):
        raise DatasetError(path, "timestamps must be finite and fit int64 nanoseconds")
    t = stamps_ns.astype(np.int64)
    steps = np.diff(t)
    if np.any(steps <= 0):
        i = int(np.argmax(steps <= 0)) + 1
        raise DatasetError(path, f"timestamps not strictly increasing at line {i + 1}")
    return t


def kitti_layout(path: str | Path) -> KittiLayout | None:
    """'odometry' or 'raw' when ``path`` is a KITTI sequence folder of that layout, else None."""
    path = Path(path)
    if (path / "calib.txt").is_file() and any((path / d).is_dir() for d, *_ in _ODOMETRY_PAIRS):
        return "odometry"
    if any((path / d / "data").is_dir() for d, *_ in _RAW_PAIRS) and (
        (path / _RAW_CALIB).is_file() or (path.parent / _RAW_CALIB).is_file()
    ):
        return "raw"
    return None


def is_kitti(path: str | Path) -> bool:
    """True when ``path`` is a KITTI odometry sequence or raw drive folder."""
    return kitti_layout(path) is not None


@dataclass(frozen=True)
class _Pair:
    left: list[Path]
    right: list[Path]
    left_key: str
    right_key: str


class KittiSequence:
    """A KITTI stereo sequence (odometry or raw layout), read lazily in time order.

    Args:
        path: an odometry sequence folder (``sequences/NN``) or a raw drive folder
            (``<date>_drive_<NNNN>_sync``).
        color: read the colour pair (``image_2``/``image_3``, ``image_02``/``image_03``) instead
            of the grey one; colour images are converted to grey.

    Example:
        >>> seq = KittiSequence("dataset/sequences/00")   # doctest: +SKIP
        >>> seq.camera.baseline_m                         # doctest: +SKIP
        0.537...
    """

    def __init__(self, path: str | Path, color: bool = False):
        self.root = Path(path)
        if not self.root.is_dir():
            raise DatasetError(self.root, "dataset folder not found")
        layout = kitti_layout(self.root)
        if layout is None:
            raise DatasetError(
                self.root,
                "not a KITTI sequence: expected an odometry folder (calib.txt, image_0/, "
                "image_1/, times.txt) or a raw drive (image_00/data/, image_01/data/, "
                f"timestamps.txt, {_RAW_CALIB} beside it or one folder up)",
            )
        self.layout: KittiLayout = layout
        pairs = _ODOMETRY_PAIRS if layout == "odometry" else _RAW_PAIRS
        left_dir, right_dir, left_key, right_key = pairs[1 if color else 0]
        suffix = "" if layout == "odometry" else "data"
        for folder in (left_dir, right_dir):
            if not (self.root / folder / suffix).is_dir():
                raise DatasetError(
                    self.root / folder / suffix,
                    f"missing image folder ({'colour' if color else 'grey'} pair)",
                )
        self._pair = _Pair(
            _images(self.root / left_dir / suffix),
            _images(self.root / right_dir / suffix),
            left_key,
            right_key,
        )
        if [p.name for p in self._pair.left] != [p.name for p in self._pair.right]:
            raise DatasetError(
                self.root / right_dir / suffix,
                f"{len(self._pair.right)} images whose names differ from the "
                f"{len(self._pair.left)} left images in {left_dir}/{suffix}",
            )
        count = len(self._pair.left)
        if layout == "odometry":
            self.calibration_path = self.root / "calib.txt"
            self.timestamps_ns = _odometry_times(self.root / "times.txt", count)
        else:
            self.calibration_path = next(
                p for p in (self.root / _RAW_CALIB, self.root.parent / _RAW_CALIB) if p.is_file()
            )
            self.timestamps_ns = _raw_times(self.root / left_dir / "timestamps.txt", count)
            t_right = _raw_times(self.root / right_dir / "timestamps.txt", count)
            worst = int(np.argmax(np.abs(t_right - self.timestamps_ns)))
            if abs(int(t_right[worst] - self.timestamps_ns[worst])) > RAW_STEREO_TOLERANCE_NS:
                raise DatasetError(
                    self.root / right_dir / "timestamps.txt",
                    f"image {worst}: {abs(int(t_right[worst] - self.timestamps_ns[worst]))} ns "
                    f"from its left image (more than {RAW_STEREO_TOLERANCE_NS} ns: not a pair)",
                )
        entries = read_kitti_calibration(self.calibration_path)
        self._read_image = GrayImageReader()
        width, height = self._image_size(entries)
        self._camera = stereo_camera_from_projections(
            entries, left_key, right_key, self.calibration_path, width, height
        )

    def _image_size(self, entries: dict[str, str]) -> tuple[int, int]:
        first = self._pair.left[0]
        height, width = self._load(first, None).shape
        if self.layout == "raw":
            camera = self._pair.left_key[-2:]
            rectified = _numbers(entries, f"S_rect_{camera}", 2, self.calibration_path)
            if (width, height) != (int(rectified[0]), int(rectified[1])):
                unrectified = entries.get(f"S_{camera}", "")
                hint = (
                    "these are the unrectified (_extract) images: use the drive's _sync download"
                    if unrectified.split()
                    and np.allclose([float(v) for v in unrectified.split()], [width, height])
                    else "the images do not belong to this calibration"
                )
                raise DatasetError(
                    first,
                    f"image is {width}x{height} but S_rect_{camera} in {self.calibration_path} "
                    f"is {int(rectified[0])}x{int(rectified[1])}: {hint}",
                )
        return width, height

    @property
    def camera(self) -> RectifiedStereoCamera:
        """The rectified stereo camera the tracker sees (the body frame is this camera)."""
        return self._camera

    def __len__(self) -> int:
        return len(self._pair.left)

    def _load(self, path: Path, expected: tuple[int, int] | None) -> np.ndarray:
        return read_sequence_image(
            self._read_image, path, expected, "the sequence's first image is"
        )

    def __getitem__(self, index: int) -> StereoFrame:
        if not -len(self) <= index < len(self):
            raise IndexError(f"frame {index} out of range (sequence has {len(self)})")
        index %= len(self)
        expected = (self._camera.height, self._camera.width)
        left = self._load(self._pair.left[index], expected)
        right = self._load(self._pair.right[index], expected)
        return StereoFrame(index=index, t_ns=int(self.timestamps_ns[index]), left=left, right=right)

    def __iter__(self) -> Iterator[StereoFrame]:
        for i in range(len(self)):
            yield self[i]

    @property
    def groundtruth_path(self) -> Path | None:
        """``<root>/poses/NN.txt`` of an odometry sequence when present, else None (raw drives
        carry GPS/INS only, which slslam does not turn into poses)."""
        if self.layout != "odometry":
            return None
        path = self.root.parent.parent / "poses" / f"{self.root.name}.txt"
        return path if path.is_file() else None

    def groundtruth(self, frame: Literal["body", "cam0", "rectified"] = "cam0") -> PoseTrajectory3D:
        """Ground-truth poses ``T_world_cam0`` with this sequence's timestamps [s]. Every frame
        name gives the same poses: KITTI's are of the rectified left camera, which is the body
        frame here."""
        del frame  # body, cam0 and the rectified left camera coincide
        path = self.groundtruth_path
        if path is None:
            raise DatasetError(self.root, "no ground truth (../../poses/NN.txt)")
        poses = read_trajectory(path, "kitti")
        if poses.num_poses != len(self):
            raise DatasetError(
                path, f"has {poses.num_poses} poses for the sequence's {len(self)} frames"
            )
        return PoseTrajectory3D(poses_se3=poses.poses_se3, timestamps=self.timestamps_ns * 1e-9)
