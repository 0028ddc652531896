"""slslam: stereo point-line visual SLAM and LiDAR registration for underground mines.

Modules
    slslam.datasets  EuRoC ASL reader with stereo rectification, calibration and trajectory files
    slslam.eval      APE / RPE via evo, metrics JSON, PNG plots
    slslam.tracking  stereo point-line tracking and local mapping (``slslam.Tracker``)
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
    "Config",
    "DatasetError",
    "InputError",
    "SlslamError",
    "Tracker",
    "TrajectoryFileError",
    "__version__",
    "default_config",
    "load_config",
    "run_sequence",
]


def __getattr__(name: str):
    """Lazy imports: ``import slslam`` stays light; the tracker loads onnxruntime, evo and the core
    only when asked for."""
    if name in ("Tracker", "run_sequence"):
        from slslam import tracking

        return getattr(tracking, name)
    if name in ("Config", "default_config", "load_config"):
        from slslam import config

        return getattr(config, name)
    raise AttributeError(f"module 'slslam' has no attribute {name!r}")
