"""EuRoC MAV datasets in the ASL folder layout.

::

    <sequence>/mav0/
        cam0/data.csv, cam0/data/<t_ns>.png, cam0/sensor.yaml     left camera
        cam1/...                                                   right camera
        imu0/data.csv, imu0/sensor.yaml                            IMU (optional)
        state_groundtruth_estimate0/data.csv                       body ground truth (optional)

Images are loaded lazily (one pair per access) and rectified with a stereo rectification built
from the two ``sensor.yaml`` files (OpenCV ``stereoRectify`` + ``remap``, in the C++ core). The
rectified left camera is the frame the tracker estimates; :attr:`EurocSequence.camera` gives its
intrinsics and baseline.

Ground truth: EuRoC gives the pose of the *body* (IMU) frame. An estimate of left-camera poses is
scored against ``T_world_cam0 = T_world_body @ T_body_cam0`` (cam0's ``T_BS``);
:meth:`EurocSequence.groundtruth` does that conversion with ``frame="cam0"``. The rectified left
camera shares cam0's optical centre, so positions (and therefore APE) are the same in both.
"""

from __future__ import annotations

import csv
import logging
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from evo.core.trajectory import PoseTrajectory3D

from slslam import _core
from slslam.datasets.calibration import CameraCalibration
from slslam.datasets.images import GrayImageReader
from slslam.datasets.trajectory_io import read_trajectory
from slslam.errors import DatasetError
from slslam.geometry import invert_transform
from slslam.timestamps import INT64_MAX, INT64_MIN
from slslam.yaml_io import short_repr

log = logging.getLogger(__name__)

MIN_BASELINE_M = 1e-3  # a stereo pair closer than this has no usable disparity


@dataclass(frozen=True)
class StereoFrame:
    """One stereo pair: ``left`` and ``right`` are uint8 H x W arrays, ``t_ns`` nanoseconds."""

    index: int
    t_ns: int
    left: np.ndarray
    right: np.ndarray


@dataclass(frozen=True)
class RectifiedStereoCamera:
    """Intrinsics shared by both rectified images, the baseline, and where the camera sits.

    ``T_body_cam`` is the pose of the rectified left camera in the body frame.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int
    baseline_m: float
    T_body_cam: np.ndarray


def find_mav0(path: str | Path) -> Path:
    """The ``mav0`` folder of an ASL sequence, given the sequence folder or ``mav0`` itself."""
    path = Path(path)
    if not path.exists():
        raise DatasetError(path, "dataset folder not found")
    for candidate in (path / "mav0", path):
        if (candidate / "cam0" / "data.csv").is_file():
            return candidate
    raise DatasetError(
        path,
        "not a EuRoC ASL folder: expected mav0/cam0/data.csv (give the folder that "
        "holds mav0/, or mav0 itself)",
    )


def is_euroc(path: str | Path) -> bool:
    """True when ``path`` looks like a EuRoC ASL sequence (or its ``mav0`` folder)."""
    try:
        find_mav0(path)
    except DatasetError:
        return False
    return True


def _read_image_index(camera_dir: Path) -> tuple[np.ndarray, list[Path]]:
    """Timestamps and image paths listed in ``<camera>/data.csv`` (files are checked later)."""
    csv_path = camera_dir / "data.csv"
    if not csv_path.is_file():
        raise DatasetError(csv_path, "missing camera index file")
    stamps: list[int] = []
    files: list[Path] = []
    with csv_path.open(newline="", encoding="utf-8") as handle:
        for row_number, row in enumerate(csv.reader(handle), start=1):
            if not row or row[0].lstrip().startswith("#"):
                continue
            if len(row) < 2:
                raise DatasetError(csv_path, f"row {row_number}: expected 'timestamp_ns,filename'")
            try:
                stamp = int(row[0].strip())
            except ValueError:
                raise DatasetError(
                    csv_path,
                    f"row {row_number}: timestamp {short_repr(row[0])} is not an integer",
                ) from None
            if not INT64_MIN <= stamp <= INT64_MAX:
                raise DatasetError(
                    csv_path,
                    f"row {row_number}: timestamp {short_repr(stamp)} does not fit int64 "
                    "nanoseconds",
                )
            stamps.append(stamp)
            files.append(camera_dir / "data" / row[1].strip())
    if not stamps:
        raise DatasetError(csv_path, "no images listed")
    t = np.asarray(stamps, dtype=np.int64)
    steps = np.diff(t)
    if np.any(steps <= 0):
        i = int(np.argmax(steps <= 0)) + 1
        raise DatasetError(
            csv_path, f"timestamps not strictly increasing at image {i} ({t[i - 1]} -> {t[i]})"
        )
    return t, files


def _pair_by_timestamp(
    t_left: np.ndarray, t_right: np.ndarray, tolerance_ns: int, left_csv: Path, right_csv: Path
) -> tuple[np.ndarray, np.ndarray]:
    """Indices (left, right) of the stereo pairs.

    Images before the later first frame or after the earlier last frame of the two cameras are
    ignored with a warning (one camera simply recorded longer). Inside the common time span every
    image must have a partner within ``tolerance_ns``; otherwise :class:`DatasetError`.
    """
    start = max(t_left[0], t_right[0]) - tolerance_ns
    end = min(t_left[-1], t_right[-1]) + tolerance_ns
    keep_left = np.flatnonzero((t_left >= start) & (t_left <= end))
    keep_right = np.flatnonzero((t_right >= start) & (t_right <= end))
    for kept, total, where in (
        (keep_left, len(t_left), left_csv),
        (keep_right, len(t_right), right_csv),
    ):
        if len(kept) < total:
            log.warning(
                "%s: %d of %d images lie outside the other camera's time span and are ignored",
                where,
                total - len(kept),
                total,
            )
    if len(keep_left) == 0 or len(keep_right) == 0:
        raise DatasetError(right_csv, "the two cameras' timestamps do not overlap at all")
    tl, tr = t_left[keep_left], t_right[keep_right]
    # Nearest right timestamp for every left one.
    j = np.clip(np.searchsorted(tr, tl), 1, max(len(tr) - 1, 1))
    j = np.where(
        np.abs(tr[j - 1] - tl) <= np.abs(tr[np.minimum(j, len(tr) - 1)] - tl),
        j - 1,
        np.minimum(j, len(tr) - 1),
    )
    unmatched = np.abs(tr[j] - tl) > tolerance_ns
    if np.any(unmatched) or len(tl) != len(tr):
        n_bad = int(np.count_nonzero(unmatched))
        first = (
            f"; first left image without a partner: t = {tl[np.argmax(unmatched)]} ns"
            if n_bad
            else ""
        )
        raise DatasetError(
            right_csv,
            f"stereo timestamps do not pair up with {left_csv.parent.name}: "
            f"{len(tl)} left and {len(tr)} right images in the common time span, {n_bad} left "
            f"images with no right image within {tolerance_ns} ns{first}",
        )
    return keep_left, keep_right[j]


def _check_files_exist(files: list[Path], csv_path: Path) -> None:
    missing = [f for f in files if not f.is_file()]
    if missing:
        raise DatasetError(
            missing[0],
            f"image file not found ({len(missing)} of {len(files)} "
            f"images listed in {csv_path} are missing)",
        )


def read_sequence_image(
    reader: GrayImageReader,
    path: Path,
    expected: tuple[int, int] | None = None,
    expected_from: str = "",
) -> np.ndarray:
    """One image of a sequence as uint8 gray; :class:`DatasetError` naming the file when it is
    unreadable or, with ``expected`` (H, W), of another size (``expected_from`` says where that
    size comes from: "image is WxH but <expected_from> WxH")."""
    try:
        image = reader(path)
    except ValueError as exc:
        raise DatasetError(
            path, str(exc).replace(f"{path}", "").strip(": ") or "unreadable image"
        ) from None
    if expected is not None and image.shape != expected:
        raise DatasetError(
            path,
            f"image is {image.shape[1]}x{image.shape[0]} but {expected_from} "
            f"{expected[1]}x{expected[0]}",
        )
    return image


def stereo_rectifier(
    left: CameraCalibration, right: CameraCalibration, where: str | Path
) -> _core.StereoRectifier:
    """The C++ rectifier of a radial-tangential stereo pair (maps built once); a rig that is not
    a left-right stereo pair raises :class:`DatasetError` naming ``where`` or the right camera's
    calibration file."""

    def radtan(c: CameraCalibration) -> _core.RadTanCamera:
        return _core.RadTanCamera(
            _core.PinholeCamera(c.fx, c.fy, c.cx, c.cy, c.width, c.height), list(c.distortion)
        )

    T_left_right = invert_transform(left.T_body_cam) @ right.T_body_cam
    t_right = T_left_right[:3, 3]  # cam1's centre in cam0's frame [m]
    if np.linalg.norm(t_right) < MIN_BASELINE_M or t_right[0] <= 0:
        raise DatasetError(
            right.path,
            f"'T_BS' puts cam1 at ({t_right[0]:.4g}, {t_right[1]:.4g}, {t_right[2]:.4g}) m "
            "in cam0's frame: a stereo pair needs cam1 to the right of cam0 (x > 0) and a "
            f"baseline of at least {MIN_BASELINE_M * 1000:g} mm (check both cameras' T_BS)",
        )
    try:
        return _core.StereoRectifier(radtan(left), radtan(right), T_left_right)
    except ValueError as exc:
        raise DatasetError(where, f"cannot rectify the stereo pair: {exc}") from None


def rectified_camera(
    rectifier: _core.StereoRectifier, left: CameraCalibration
) -> RectifiedStereoCamera:
    """The rectified stereo camera the tracker sees, placed in the body frame."""
    pinhole = rectifier.rectified_camera
    T_cam0_rect = np.eye(4)
    T_cam0_rect[:3, :3] = np.asarray(rectifier.R_rect_left).T
    return RectifiedStereoCamera(
        fx=pinhole.fx,
        fy=pinhole.fy,
        cx=pinhole.cx,
        cy=pinhole.cy,
        width=pinhole.width,
        height=pinhole.height,
        baseline_m=rectifier.baseline_m,
        T_body_cam=left.T_body_cam @ T_cam0_rect,
    )


class EurocSequence:
    """A EuRoC ASL stereo sequence, read lazily in time order.

    Args:
        path: the folder that holds ``mav0/`` (or ``mav0`` itself).
        rectify: return rectified images (default) or the raw distorted ones.
        stereo_tolerance_ns: largest left/right timestamp difference accepted as one pair.
            EuRoC's cameras are hardware-synchronised, so the default demands equality.

    Example:
        >>> seq = EurocSequence("V1_01_easy")          # doctest: +SKIP
        >>> for frame in seq:                          # doctest: +SKIP
        ...     track(frame.left, frame.right, frame.t_ns)
    """

    def __init__(self, path: str | Path, rectify: bool = True, stereo_tolerance_ns: int = 0):
        self.root = find_mav0(path)
        self.rectify = rectify
        self.left_calibration = CameraCalibration.from_yaml(self.root / "cam0" / "sensor.yaml")
        self.right_calibration = CameraCalibration.from_yaml(self.root / "cam1" / "sensor.yaml")
        t_left, self._left_files = _read_image_index(self.root / "cam0")
        t_right, self._right_files = _read_image_index(self.root / "cam1")
        left_idx, right_idx = _pair_by_timestamp(
            t_left,
            t_right,
            stereo_tolerance_ns,
            self.root / "cam0" / "data.csv",
            self.root / "cam1" / "data.csv",
        )
        self._pairs = list(zip(left_idx.tolist(), right_idx.tolist(), strict=True))
        _check_files_exist([self._left_files[i] for i in left_idx], self.root / "cam0" / "data.csv")
        _check_files_exist(
            [self._right_files[j] for j in right_idx], self.root / "cam1" / "data.csv"
        )
        self.timestamps_ns = t_left[left_idx]
        self._read_image = GrayImageReader()  # 16-bit PNGs scaled by their real depth
        self._rectifier = self._build_rectifier()

    def _build_rectifier(self) -> _core.StereoRectifier:
        return stereo_rectifier(self.left_calibration, self.right_calibration, self.root)

    @property
    def camera(self) -> RectifiedStereoCamera:
        """The rectified stereo camera the tracker sees."""
        return rectified_camera(self._rectifier, self.left_calibration)

    @property
    def rectifier(self) -> _core.StereoRectifier:
        """The C++ rectifier (maps built once)."""
        return self._rectifier

    def __len__(self) -> int:
        return len(self._pairs)

    def _load(self, path: Path) -> np.ndarray:
        expected = (self.left_calibration.height, self.left_calibration.width)
        return read_sequence_image(self._read_image, path, expected, "the calibration is for")

    def __getitem__(self, index: int) -> StereoFrame:
        if not -len(self) <= index < len(self):
            raise IndexError(f"frame {index} out of range (sequence has {len(self)})")
        index %= len(self)
        i_left, i_right = self._pairs[index]
        left = self._load(self._left_files[i_left])
        right = self._load(self._right_files[i_right])
        if self.rectify:
            left, right = self._rectifier.rectify(left, right)
        return StereoFrame(index=index, t_ns=int(self.timestamps_ns[index]), left=left, right=right)

    def __iter__(self) -> Iterator[StereoFrame]:
        for i in range(len(self)):
            yield self[i]

    @property
    def groundtruth_path(self) -> Path | None:
        """The body ground-truth csv, or None when the sequence has none."""
        path = self.root / "state_groundtruth_estimate0" / "data.csv"
        return path if path.is_file() else None

    def groundtruth(self, frame: Literal["body", "cam0", "rectified"] = "cam0") -> PoseTrajectory3D:
        """Ground-truth poses ``T_world_<frame>`` (timestamps in seconds).

        ``cam0`` (default) composes the body poses with cam0's ``T_BS``; ``rectified`` adds the
        rectifying rotation. Raises :class:`DatasetError` when the sequence has no ground truth.
        """
        path = self.groundtruth_path
        if path is None:
            raise DatasetError(self.root, "no ground truth (state_groundtruth_estimate0/data.csv)")
        traj = read_trajectory(path, "euroc")
        if frame == "body":
            return traj
        T_body_frame = (
            self.left_calibration.T_body_cam if frame == "cam0" else self.camera.T_body_cam
        )
        traj.transform(T_body_frame, right_mul=True)
        return traj

    def imu(self) -> dict[str, np.ndarray]:
        """IMU samples: ``t_ns`` (int64, N), ``gyro`` [rad/s] and ``acc`` [m/s^2] (N x 3)."""
        path = self.root / "imu0" / "data.csv"
        if not path.is_file():
            raise DatasetError(path, "no IMU data in this sequence")
        try:
            table = np.loadtxt(path, delimiter=",", comments="#", ndmin=2, dtype=np.float64)
            stamps = np.loadtxt(
                path, delimiter=",", comments="#", usecols=0, dtype=np.int64, ndmin=1
            )
        except (ValueError, OverflowError) as exc:
            raise DatasetError(path, f"malformed IMU csv ({short_repr(str(exc), 120)})") from None
        if table.shape[1] < 7:
            raise DatasetError(path, f"expected 7 columns (t, w_xyz, a_xyz), got {table.shape[1]}")
        return {"t_ns": stamps, "gyro": table[:, 1:4], "acc": table[:, 4:7]}
