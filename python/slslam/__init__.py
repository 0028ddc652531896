"""slslam: stereo point-line visual SLAM and LiDAR registration for underground mines.

Modules
    slslam.datasets  EuRoC ASL reader with stereo rectification, calibration and trajectory files
    slslam.eval      APE / RPE via evo, metrics JSON, PNG plots
    slslam.cli       the ``slslam`` command
    slslam._core     the C++ core (camera geometry, rectification, features)
"""

from slslam._version import __version__
from slslam.errors import (
    CalibrationError,
    DatasetError,
    InputError,
    SlslamError,
    TrajectoryFileError,
)

__all__ = [
    "CalibrationError",
    "DatasetError",
    "InputError",
    "SlslamError",
    "TrajectoryFileError",
    "__version__",
]
