"""Shared fixtures: the real data in ../shared/data (skipped when absent) and small EuRoC-like
sequences made on the spot."""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
SHARED_DATA = REPO.parent / "shared" / "data"


def load_benchmark(script: str):
    """Imports benchmarks/<script> as a module (with benchmarks/ on sys.path while it loads and
    runs, for its neighbour common.py); a generator for module-scoped fixtures to yield from."""
    folder = str(REPO / "benchmarks")
    sys.path.insert(0, folder)
    try:
        spec = importlib.util.spec_from_file_location(
            Path(script).stem, REPO / "benchmarks" / script
        )
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.path.remove(folder)


def shared_path(*parts: str) -> Path:
    """A path under ../shared/data, or skip the test with the reason when it is absent."""
    path = SHARED_DATA.joinpath(*parts)
    if not path.exists():
        pytest.skip(f"real data not available here: {path} (present only in the slslam workplace)")
    return path


@pytest.fixture
def euroc_micro() -> Path:
    """The real EuRoC V1_01 excerpt (95 stereo pairs)."""
    return shared_path("euroc_v101_micro")


CAMERA_YAML = """%YAML:1.0
sensor_type: camera
T_BS:
  cols: 4
  rows: 4
  data: [{T}]
rate_hz: 20
resolution: [{width}, {height}]
camera_model: pinhole
intrinsics: [{fx}, {fx}, {cx}, {cy}]
distortion_model: radial-tangential
distortion_coefficients: [{k1}, 0.01, 0.0, 0.0]
"""


def camera_yaml(x_offset_m: float, width: int = 64, height: int = 48, k1: float = -0.05) -> str:
    """A camera sensor.yaml of our own: identity rotation, shifted along body x."""
    T = np.eye(4)
    T[0, 3] = x_offset_m
    return CAMERA_YAML.format(
        T=", ".join(f"{v:.6f}" for v in T.ravel()),
        width=width,
        height=height,
        fx=50.0,
        cx=width / 2 - 0.5,
        cy=height / 2 - 0.5,
        k1=k1,
    )


MakeEuroc = Callable[..., Path]


@pytest.fixture
def make_euroc(tmp_path: Path) -> MakeEuroc:
    """Factory for a tiny EuRoC ASL folder with random-texture images.

    Keyword arguments: ``n`` frames, ``right_stamps`` to override cam1's timestamps, ``size``
    (width, height) of the images written.
    """
    from slslam import _core

    def make(
        n: int = 5, right_stamps: list[int] | None = None, size: tuple[int, int] = (64, 48)
    ) -> Path:
        root = tmp_path / "seq"
        mav0 = root / "mav0"
        rng = np.random.default_rng(0)
        left_stamps = [1_000_000_000 + 50_000_000 * i for i in range(n)]
        for cam, stamps, x in (
            ("cam0", left_stamps, 0.0),
            ("cam1", right_stamps or left_stamps, 0.11),
        ):
            (mav0 / cam / "data").mkdir(parents=True, exist_ok=True)
            (mav0 / cam / "sensor.yaml").write_text(camera_yaml(x))
            lines = ["#timestamp [ns],filename"]
            for t in stamps:
                image = rng.integers(0, 255, size=(size[1], size[0]), dtype=np.uint8)
                _core.write_image(str(mav0 / cam / "data" / f"{t}.png"), image)
                lines.append(f"{t},{t}.png")
            (mav0 / cam / "data.csv").write_text("\n".join(lines) + "\n")
        return root

    return make


def ros_header(typestore, t_ns: int, frame_id: str = "cam"):
    """A std_msgs/Header stamped ``t_ns`` for a rosbags typestore (ROS1's has ``seq``)."""
    Time = typestore.types["builtin_interfaces/msg/Time"]
    Header = typestore.types["std_msgs/msg/Header"]
    stamp = Time(sec=t_ns // 10**9, nanosec=t_ns % 10**9)
    if "seq" in Header.__dataclass_fields__:  # ROS1's Header
        return Header(seq=0, stamp=stamp, frame_id=frame_id)
    return Header(stamp=stamp, frame_id=frame_id)


def ros_imu_message(typestore, t_ns: int, gyro, acc):
    """A sensor_msgs/Imu with the given angular velocity [rad/s] and acceleration [m/s^2]."""
    Vector3 = typestore.types["geometry_msgs/msg/Vector3"]
    Quaternion = typestore.types["geometry_msgs/msg/Quaternion"]
    return typestore.types["sensor_msgs/msg/Imu"](
        header=ros_header(typestore, t_ns, "imu"),
        orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
        orientation_covariance=np.zeros(9),
        angular_velocity=Vector3(x=gyro[0], y=gyro[1], z=gyro[2]),
        angular_velocity_covariance=np.zeros(9),
        linear_acceleration=Vector3(x=acc[0], y=acc[1], z=acc[2]),
        linear_acceleration_covariance=np.zeros(9),
    )
