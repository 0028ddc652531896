"""Dataset readers: EuRoC ASL and KITTI (odometry, raw) sequences, calibration files,
trajectory files."""

from slslam.datasets.calibration import CameraCalibration, ImuCalibration
from slslam.datasets.euroc import (
    EurocSequence,
    RectifiedStereoCamera,
    StereoFrame,
    find_mav0,
    is_euroc,
)
from slslam.datasets.kitti import KittiSequence, is_kitti, kitti_layout
from slslam.datasets.trajectory_io import detect_format, read_trajectory, write_trajectory

__all__ = [
    "CameraCalibration",
    "EurocSequence",
    "ImuCalibration",
    "KittiSequence",
    "RectifiedStereoCamera",
    "StereoFrame",
    "detect_format",
    "find_mav0",
    "is_euroc",
    "is_kitti",
    "kitti_layout",
    "read_trajectory",
    "write_trajectory",
]
