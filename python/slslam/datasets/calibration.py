"""Sensor calibration files in EuRoC's ``sensor.yaml`` form.

A camera file gives ``T_BS`` (pose of the sensor in the body/IMU frame), ``resolution``,
``intrinsics`` (fu, fv, cu, cv), ``distortion_model`` (only ``radial-tangential``) and
``distortion_coefficients`` (k1, k2, p1, p2). An IMU file gives ``T_BS``, ``rate_hz`` and the noise
densities. Missing keys and invalid values raise :class:`~slslam.errors.CalibrationError` naming the
file and the key.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from slslam.errors import CalibrationError
from slslam.geometry import is_rigid_transform
from slslam.yaml_io import read_yaml, short_repr

SUPPORTED_DISTORTION_MODELS = ("radial-tangential",)
# What can still be a camera: larger images, or radial-tangential coefficients beyond these
# bounds (|k1|, |k2| <= 10, |p1|, |p2| <= 1; real lenses stay well under 1), are refused.
MAX_RESOLUTION_PX = 20_000
MAX_ABS_RADIAL = 10.0
MAX_ABS_TANGENTIAL = 1.0


def load_yaml(path: str | Path) -> dict[str, Any]:
    """Read a YAML file, accepting OpenCV's ``%YAML:1.0`` header that PyYAML rejects.

    At most 1 MiB, no aliases, the C loader when available (see :mod:`slslam.yaml_io`).
    """
    path = Path(path)
    data = read_yaml(path, CalibrationError, strip_opencv_header=True)
    if not isinstance(data, dict):
        raise CalibrationError(path, "expected a YAML mapping at the top level")
    return data


def require_key(data: dict[str, Any], key: str, path: Path) -> Any:
    """``data[key]``; CalibrationError naming ``path`` and the key when it is missing."""
    if key not in data:
        raise CalibrationError(path, f"missing key '{key}'")
    return data[key]


def numbers_of(value: Any, count: int, key: str, path: Path) -> np.ndarray:
    """``value`` (a list of numbers or of their texts) as ``count`` finite floats;
    CalibrationError naming ``path`` and ``key`` otherwise."""
    try:
        array = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError, OverflowError):
        raise CalibrationError(
            path, f"'{key}' must be a list of numbers, got {short_repr(value)}"
        ) from None
    if array.size != count:
        raise CalibrationError(path, f"'{key}' must have {count} numbers, got {array.size}")
    if not np.all(np.isfinite(array)):
        raise CalibrationError(path, f"'{key}' contains NaN or Inf")
    return array


def _transform(data: dict[str, Any], path: Path) -> np.ndarray:
    raw = require_key(data, "T_BS", path)
    values = raw.get("data") if isinstance(raw, dict) else raw
    if values is None:
        raise CalibrationError(path, "'T_BS' has no 'data' list")
    T = numbers_of(values, 16, "T_BS", path).reshape(4, 4)
    if not is_rigid_transform(T):
        raise CalibrationError(path, "'T_BS' is not a rigid transform (rotation block or last row)")
    return T


@dataclass(frozen=True)
class CameraCalibration:
    """One camera of a EuRoC-style rig.

    Attributes:
        T_body_cam: pose of the camera in the body (IMU) frame, 4x4, metres.
        width, height: image size in pixels.
        fx, fy, cx, cy: pinhole intrinsics in pixels.
        distortion: radial-tangential coefficients (k1, k2, p1, p2).
        rate_hz: frame rate, if the file states it.
    """

    path: Path
    T_body_cam: np.ndarray
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple[float, float, float, float]
    rate_hz: float | None = None

    @classmethod
    def from_yaml(cls, path: str | Path) -> CameraCalibration:
        """Parse a EuRoC camera ``sensor.yaml``."""
        path = Path(path)
        data = load_yaml(path)
        T = _transform(data, path)
        width, height = numbers_of(require_key(data, "resolution", path), 2, "resolution", path)
        if width <= 0 or height <= 0 or width != int(width) or height != int(height):
            raise CalibrationError(
                path, f"'resolution' must be two positive integers, got {width:g} x {height:g}"
            )
        if max(width, height) > MAX_RESOLUTION_PX:
            raise CalibrationError(
                path,
                f"'resolution' {width:g} x {height:g} is not a camera image "
                f"(at most {MAX_RESOLUTION_PX} px a side)",
            )
        fx, fy, cx, cy = numbers_of(require_key(data, "intrinsics", path), 4, "intrinsics", path)
        if fx <= 0 or fy <= 0:
            raise CalibrationError(
                path, f"'intrinsics' focal lengths must be > 0, got {fx:g}, {fy:g}"
            )
        if not (-width < cx < 2 * width and -height < cy < 2 * height):
            raise CalibrationError(
                path,
                f"'intrinsics' principal point ({cx:g}, {cy:g}) lies far outside the "
                f"{width:g} x {height:g} image",
            )
        model = require_key(data, "distortion_model", path)
        if model not in SUPPORTED_DISTORTION_MODELS:
            raise CalibrationError(
                path,
                f"distortion_model '{model}' is not supported "
                f"(supported: {', '.join(SUPPORTED_DISTORTION_MODELS)})",
            )
        dist = numbers_of(
            require_key(data, "distortion_coefficients", path), 4, "distortion_coefficients", path
        )
        for name, value, bound in zip(
            ("k1", "k2", "p1", "p2"),
            dist,
            (MAX_ABS_RADIAL, MAX_ABS_RADIAL, MAX_ABS_TANGENTIAL, MAX_ABS_TANGENTIAL),
            strict=True,
        ):
            if abs(value) > bound:
                raise CalibrationError(
                    path,
                    f"'distortion_coefficients' {name} = {value:g} is beyond +-{bound:g}: "
                    "not a radial-tangential lens model",
                )
        rate = data.get("rate_hz")
        if rate is not None:
            (rate,) = numbers_of(rate, 1, "rate_hz", path)
            if rate <= 0:
                raise CalibrationError(path, f"'rate_hz' must be > 0, got {rate:g}")
        return cls(
            path=path,
            T_body_cam=T,
            width=int(width),
            height=int(height),
            fx=float(fx),
            fy=float(fy),
            cx=float(cx),
            cy=float(cy),
            distortion=tuple(float(d) for d in dist),  # type: ignore[arg-type]
            rate_hz=None if rate is None else float(rate),
        )


@dataclass(frozen=True)
class ImuCalibration:
    """The IMU of a EuRoC-style rig (continuous-time noise densities, SI units)."""

    path: Path
    T_body_imu: np.ndarray
    rate_hz: float
    gyroscope_noise_density: float  # [rad / s / sqrt(Hz)]
    gyroscope_random_walk: float  # [rad / s^2 / sqrt(Hz)]
    accelerometer_noise_density: float  # [m / s^2 / sqrt(Hz)]
    accelerometer_random_walk: float  # [m / s^3 / sqrt(Hz)]

    @classmethod
    def from_yaml(cls, path: str | Path) -> ImuCalibration:
        """Parse a EuRoC IMU ``sensor.yaml``."""
        path = Path(path)
        data = load_yaml(path)
        values = {}
        for key in (
            "rate_hz",
            "gyroscope_noise_density",
            "gyroscope_random_walk",
            "accelerometer_noise_density",
            "accelerometer_random_walk",
        ):
            (value,) = numbers_of(require_key(data, key, path), 1, key, path)
            if value < 0 or (key == "rate_hz" and value == 0):
                raise CalibrationError(path, f"'{key}' must be positive, got {value}")
            values[key] = float(value)
        return cls(path=path, T_body_imu=_transform(data, path), **values)
