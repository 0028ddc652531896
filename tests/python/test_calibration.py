from pathlib import Path

import numpy as np
import pytest

from slslam.datasets import CameraCalibration, ImuCalibration
from slslam.errors import CalibrationError

from conftest import camera_yaml, shared_path


def test_reads_real_euroc_camera_and_imu_files():
    cam = CameraCalibration.from_yaml(shared_path("euroc_calib", "euroc_cam0_sensor.yaml"))
    assert (cam.width, cam.height) == (752, 480)
    assert cam.fx == pytest.approx(458.654)
    assert cam.distortion[0] == pytest.approx(-0.28340811)
    assert cam.T_body_cam[0, 3] == pytest.approx(-0.0216401454975)
    imu = ImuCalibration.from_yaml(shared_path("euroc_calib", "euroc_imu0_sensor.yaml"))
    assert imu.rate_hz == 200
    assert imu.gyroscope_noise_density > 0


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "sensor.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "key", ["T_BS", "resolution", "intrinsics", "distortion_model", "distortion_coefficients"]
)
def test_missing_key_names_file_and_key(tmp_path, key):
    lines = [line for line in camera_yaml(0.0).splitlines() if not line.startswith(key)]
    if key == "T_BS":  # drop its nested block too
        lines = [line for line in lines if not line.startswith(("  cols", "  rows", "  data"))]
    path = _write(tmp_path, "\n".join(lines))
    with pytest.raises(CalibrationError, match=f"{path}.*missing key '{key}'"):
        CameraCalibration.from_yaml(path)


def test_non_rigid_transform_is_rejected(tmp_path):
    text = camera_yaml(0.0).replace("data: [1.000000", "data: [2.000000")
    with pytest.raises(CalibrationError, match="not a rigid transform"):
        CameraCalibration.from_yaml(_write(tmp_path, text))


def test_wrong_counts_and_values_are_rejected(tmp_path):
    with pytest.raises(CalibrationError, match="'intrinsics' must have 4 numbers, got 3"):
        CameraCalibration.from_yaml(
            _write(
                tmp_path, camera_yaml(0.0).replace("intrinsics: [50.0, 50.0,", "intrinsics: [50.0,")
            )
        )
    with pytest.raises(CalibrationError, match="NaN"):
        CameraCalibration.from_yaml(
            _write(tmp_path, camera_yaml(0.0).replace("intrinsics: [50.0", "intrinsics: [.nan"))
        )
    with pytest.raises(CalibrationError, match="not supported"):
        CameraCalibration.from_yaml(
            _write(tmp_path, camera_yaml(0.0).replace("radial-tangential", "equidistant"))
        )


def test_missing_and_invalid_yaml_files(tmp_path):
    with pytest.raises(CalibrationError, match="file not found"):
        CameraCalibration.from_yaml(tmp_path / "nope.yaml")
    with pytest.raises(CalibrationError, match="not valid YAML"):
        CameraCalibration.from_yaml(_write(tmp_path, "T_BS: [1, 2\nfoo: : :"))


def test_parsed_transform_matches_written_values(tmp_path):
    cam = CameraCalibration.from_yaml(_write(tmp_path, camera_yaml(0.25)))
    expected = np.eye(4)
    expected[0, 3] = 0.25
    np.testing.assert_allclose(cam.T_body_cam, expected)
