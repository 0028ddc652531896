"""Dataset readers: EuRoC ASL sequences, calibration files, trajectory files."""

from slslam.datasets.calibration import CameraCalibration, ImuCalibration
from slslam.datasets.euroc import (
    EurocSequence,
    RectifiedStereoCamera,
    StereoFrame,
    find_mav0,
    is_euroc,
)
from slslam.datasets.trajectory_io import detect_format, read_trajectory, write_trajectory

__all__ = [
    "CameraCalibration",
    "EurocSequence",
    "ImuCalibration",
    "RectifiedStereoCamera",
    "StereoFrame",
    "detect_format",
    "find_mav0",
    "is_euroc",
    "read_trajectory",
    "write_trajectory",
]
