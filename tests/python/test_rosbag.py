"""ROS bags without ROS: a simulated sequence written by ``rosbags`` into ROS1 (.bag) and ROS2
(.db3, .mcap) bags, as Image and CompressedImage, read back by ``RosbagSequence``; the tracker
gives the same trajectory on the bag as on the ASL folder, through the API and ``slslam run``."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from typer.testing import CliRunner

from slslam.cli import app
from slslam.config import Config, default_config
from slslam.datasets import EurocSequence
from slslam.datasets.rosbag import (
    RosbagSequence,
    bag_topics,
    decode_image,
    is_rosbag,
    kalibr_topics,
    load_stereo_calibration,
)
from slslam.errors import CalibrationError, DatasetError
from slslam.geometry import invert_transform
from slslam.sim import SimOptions, Simulator
from slslam.tracking import run_sequence

from conftest import ros_header, ros_imu_message

FRAMES = 24
LEFT, RIGHT, IMU = "/cam0/image_raw", "/cam1/image_raw", "/imu0"


@pytest.fixture(scope="module")
def asl(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("rosbag") / "seq"
    Simulator(SimOptions(preset="loop", frames=FRAMES, lidar=False)).write(out, progress=False)
    return out


def _image_msg(typestore, image: np.ndarray, t_ns: int, kind: str):
    """``kind``: mono8 / bgr8 / rgb8 (Image) or png (CompressedImage)."""
    if kind == "png":
        ok, data = cv2.imencode(".png", image)
        assert ok
        return typestore.types["sensor_msgs/msg/CompressedImage"](
            header=ros_header(typestore, t_ns), format="png", data=data.reshape(-1)
        )
    if kind in ("bgr8", "rgb8"):
        image = np.repeat(image[:, :, None], 3, axis=2)
    channels = 1 if image.ndim == 2 else image.shape[2]
    return typestore.types["sensor_msgs/msg/Image"](
        header=ros_header(typestore, t_ns),
        height=image.shape[0],
        width=image.shape[1],
        encoding=kind,
        is_bigendian=0,
        step=image.shape[1] * channels,
        data=np.ascontiguousarray(image).reshape(-1),
    )


def _camera_info_msgs(typestore, seq: EurocSequence, t_ns: int):
    """CameraInfo of both cameras as a ROS stereo calibration writes them: K, D (plumb_bob),
    R (rectified <- camera) and P (the right one with -fx * baseline)."""
    rectifier, cam = seq.rectifier, seq.camera
    P = np.array([[cam.fx, 0, cam.cx, 0], [0, cam.fy, cam.cy, 0], [0, 0, 1, 0]], dtype=float)
    P_right = P.copy()
    P_right[0, 3] = -cam.fx * cam.baseline_m
    Info = typestore.types["sensor_msgs/msg/CameraInfo"]
    Roi = typestore.types["sensor_msgs/msg/RegionOfInterest"]
    upper = "D" in Info.__dataclass_fields__  # ROS1 spells the arrays D K R P
    messages = []
    for c, R, proj in (
        (seq.left_calibration, np.asarray(rectifier.R_rect_left), P),
        (seq.right_calibration, np.asarray(rectifier.R_rectright_right), P_right),
    ):
        K = np.array([[c.fx, 0, c.cx], [0, c.fy, c.cy], [0, 0, 1]], dtype=float)
        arrays = {"d": np.array([*c.distortion, 0.0]), "k": K.reshape(-1), "r": R.reshape(-1),
                  "p": proj.reshape(-1)}  # fmt: skip
        messages.append(
            Info(
                header=ros_header(typestore, t_ns),
                height=c.height,
                width=c.width,
                distortion_model="plumb_bob",
                **{(k.upper() if upper else k): v for k, v in arrays.items()},
                binning_x=0,
                binning_y=0,
                roi=Roi(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False),
            )
        )
    return messages


def write_bag(asl: Path, out: Path, storage: str, kind: str, camera_info: bool = False) -> Path:
    """The ASL sequence's raw images (and IMU) as a bag: ``storage`` ros1, sqlite3 or mcap;
    ``camera_info`` adds /cam0/camera_info and /cam1/camera_info."""
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore

    seq = EurocSequence(asl, rectify=False)
    imu = seq.imu()
    ros1 = storage == "ros1"
    typestore = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    image_type = "sensor_msgs/msg/CompressedImage" if kind == "png" else "sensor_msgs/msg/Image"
    if ros1:
        writer = Writer1(out)
        serialize = typestore.serialize_ros1
    else:
        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(out, version=9, storage_plugin=plugin)
        serialize = typestore.serialize_cdr
    with writer:
        left = writer.add_connection(LEFT, image_type, typestore=typestore)
        right = writer.add_connection(RIGHT, image_type, typestore=typestore)
        imu_conn = writer.add_connection(IMU, "sensor_msgs/msg/Imu", typestore=typestore)
        if camera_info:
            info_type = "sensor_msgs/msg/CameraInfo"
            t0 = int(seq.timestamps_ns[0])
            for topic, msg in zip(
                ("/cam0/camera_info", "/cam1/camera_info"),
                _camera_info_msgs(typestore, EurocSequence(asl), t0),
                strict=True,
            ):
                conn = writer.add_connection(topic, info_type, typestore=typestore)
                writer.write(conn, t0, serialize(msg, info_type))
        Imu = typestore.types["sensor_msgs/msg/Imu"]
        in_span = imu["t_ns"] <= seq.timestamps_ns[-1]
        for t, w, a in zip(
            imu["t_ns"][in_span], imu["gyro"][in_span], imu["acc"][in_span], strict=True
        ):
            msg = ros_imu_message(typestore, int(t), w, a)
            writer.write(imu_conn, int(t), serialize(msg, Imu.__msgtype__))
        for frame in seq:
            # Received a few ms after the exposure, right before left: the header stamp counts.
            for conn, image, delay in (
                (right, frame.right, 3_000_000),
                (left, frame.left, 4_000_000),
            ):
                msg = _image_msg(typestore, image, frame.t_ns, kind)
                writer.write(conn, frame.t_ns + delay, serialize(msg, image_type))
    return out


def calibration(asl: Path) -> list[Path]:
    return [asl / "mav0" / "cam0" / "sensor.yaml", asl / "mav0" / "cam1" / "sensor.yaml"]


def orb_config() -> Config:
    """ORB with its preset, as a config file naming ORB gives it (the CLI test below)."""
    return default_config("orb")


@pytest.fixture(scope="module")
def folder_run(asl, tmp_path_factory):
    out = tmp_path_factory.mktemp("folder_run")
    run_sequence(asl, out, orb_config(), progress=False)
    return (out / "trajectory.tum").read_text()


@pytest.mark.parametrize(
    ("storage", "kind", "name"),
    [("ros1", "mono8", "seq.bag"), ("sqlite3", "png", "seq_db3"), ("mcap", "rgb8", "seq_mcap")],
)
def test_bag_run_equals_folder_run(asl, folder_run, tmp_path, storage, kind, name):
    bag = write_bag(asl, tmp_path / name, storage, kind)
    assert is_rosbag(bag)
    if storage != "ros1":  # the storage file itself is accepted too
        storage_file = next(p for p in bag.iterdir() if p.suffix in (".db3", ".mcap"))
        assert storage_file.suffix == (".mcap" if storage == "mcap" else ".db3")
        assert is_rosbag(storage_file)
    topics = {t.topic: t for t in bag_topics(bag)}
    assert topics[LEFT].count == FRAMES and topics[RIGHT].count == FRAMES
    assert topics[IMU].msgtype == "sensor_msgs/msg/Imu"

    folder = EurocSequence(asl)
    with RosbagSequence(bag, LEFT, RIGHT, calibration(asl), imu_topic=IMU) as seq:
        assert len(seq) == FRAMES
        assert np.array_equal(seq.timestamps_ns, folder.timestamps_ns)
        assert (
            seq.camera.fx == folder.camera.fx and seq.camera.baseline_m == folder.camera.baseline_m
        )
        for i in (0, FRAMES - 1, 5):  # random access too
            assert np.array_equal(seq[i].left, folder[i].left)
            assert np.array_equal(seq[i].right, folder[i].right)
        imu = seq.imu()
        expected = folder.imu()
        n = len(imu["t_ns"])
        assert n > 0 and np.array_equal(imu["t_ns"], expected["t_ns"][:n])
        assert np.allclose(imu["gyro"], expected["gyro"][:n])
        out = tmp_path / "run"
        run_sequence(seq, out, orb_config(), progress=False)
    assert (out / "trajectory.tum").read_text() == folder_run


def test_cli_run_and_info_on_a_bag(asl, folder_run, tmp_path):
    bag = write_bag(asl, tmp_path / "cli.bag", "ros1", "mono8")
    runner = CliRunner()
    info = runner.invoke(app, ["info", str(bag)])
    assert info.exit_code == 0, info.output
    assert (
        LEFT in info.output
        and "sensor_msgs/msg/Image" in info.output
        and str(FRAMES) in info.output
    )
    config = tmp_path / "orb.yaml"
    config.write_text("features:\n  point_frontend: orb\n")
    cal = calibration(asl)
    args = ["run", str(bag), "--left", LEFT, "--right", RIGHT, "--imu", IMU, "--calib", str(cal[0]),
            "--calib", str(cal[1]), "--config", str(config), "--out", str(tmp_path / "out"),
            "--no-progress"]  # fmt: skip
    done = runner.invoke(app, args)
    assert done.exit_code == 0, done.output
    assert (tmp_path / "out" / "trajectory.tum").read_text() == folder_run
    missing = runner.invoke(app, ["run", str(bag), "--out", str(tmp_path / "o2")])
    assert missing.exit_code != 0 and "--left and --right" in str(missing.exception)


def test_kalibr_camchain_gives_the_euroc_calibration(asl, tmp_path):
    left, right = load_stereo_calibration(calibration(asl))
    T_cam1_cam0 = invert_transform(right.T_body_cam) @ left.T_body_cam
    T_cam_imu = invert_transform(left.T_body_cam)

    def camera(c, extra: str) -> str:
        return (
            f"  camera_model: pinhole\n  intrinsics: [{c.fx}, {c.fy}, {c.cx}, {c.cy}]\n"
            f"  distortion_model: radtan\n  distortion_coeffs: {list(c.distortion)}\n"
            f"  resolution: [{c.width}, {c.height}]\n{extra}"
        )

    rows = lambda T: "\n".join(f"  - {list(map(float, r))}" for r in T)  # noqa: E731
    path = tmp_path / "camchain.yaml"
    path.write_text(
        "cam0:\n" + camera(left, f"  T_cam_imu:\n{rows(T_cam_imu)}\n  rostopic: {LEFT}\n")
        + "cam1:\n" + camera(right, f"  T_cn_cnm1:\n{rows(T_cam1_cam0)}\n  rostopic: {RIGHT}\n")
    )  # fmt: skip
    k_left, k_right = load_stereo_calibration([path])
    assert np.allclose(k_left.T_body_cam, left.T_body_cam)
    assert np.allclose(k_right.T_body_cam, right.T_body_cam)
    assert (k_right.fx, k_right.width, k_right.distortion) == (
        right.fx,
        right.width,
        right.distortion,
    )
    assert kalibr_topics(path) == (LEFT, RIGHT)
    # An ASL folder serves as calibration too.
    assert np.allclose(load_stereo_calibration([asl])[1].T_body_cam, right.T_body_cam)


def test_bad_bags_and_calibrations_name_file_and_key(asl, tmp_path):
    bag = write_bag(asl, tmp_path / "bad.bag", "ros1", "mono8")
    with pytest.raises(DatasetError, match=r"no topic '/cam9'.*for the right camera"):
        RosbagSequence(bag, LEFT, "/cam9", calibration(asl))
    with pytest.raises(DatasetError, match="holds sensor_msgs/msg/Imu"):
        RosbagSequence(bag, LEFT, IMU, calibration(asl))
    junk = tmp_path / "junk.bag"
    junk.write_bytes(b"not a bag at all")
    with pytest.raises(DatasetError, match="cannot read the bag") as info:
        bag_topics(junk)
    assert str(junk) in str(info.value)
    with pytest.raises(DatasetError, match="not a ROS bag"):
        bag_topics(tmp_path)
    camchain = tmp_path / "c.yaml"
    camchain.write_text("cam0: {camera_model: pinhole}\ncam1: {T_cn_cnm1: [[1, 0], [0, 1]]}\n")
    with pytest.raises(CalibrationError, match=r"cam1\.T_cn_cnm1") as info:
        load_stereo_calibration([camchain])
    assert str(camchain) in str(info.value)
    with pytest.raises(CalibrationError, match="give --calib twice"):
        load_stereo_calibration([calibration(asl)[0]])


def test_image_encodings_decode_to_the_same_gray():
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_HUMBLE)
    rng = np.random.default_rng(0)
    gray = rng.integers(0, 256, (20, 30), dtype=np.uint8)
    decoded = {}
    for kind in ("mono8", "bgr8", "rgb8", "png"):
        msgtype = "x/CompressedImage" if kind == "png" else "x/Image"
        decoded[kind] = decode_image(_image_msg(typestore, gray, 1, kind), msgtype, "t")
    assert np.array_equal(decoded["mono8"], gray) and np.array_equal(decoded["png"], gray)
    assert np.array_equal(decoded["bgr8"][:, :, 1], gray) and decoded["rgb8"].shape == (20, 30, 3)
    # 16-bit big-endian with row padding.
    Image = typestore.types["sensor_msgs/msg/Image"]
    deep = rng.integers(0, 65536, (4, 5), dtype=np.uint16)
    padded = np.zeros((4, 12), np.uint8)
    padded[:, :10] = deep.astype(">u2").view(np.uint8).reshape(4, 10)
    msg = Image(header=ros_header(typestore, 1), height=4, width=5, encoding="mono16",
                is_bigendian=1, step=12, data=padded.reshape(-1))  # fmt: skip
    assert np.array_equal(decode_image(msg, "sensor_msgs/msg/Image", "t"), deep)
    msg.encoding = "yuv422"
    with pytest.raises(DatasetError, match="encoding 'yuv422' is not supported"):
        decode_image(msg, "sensor_msgs/msg/Image", "t")


@pytest.mark.parametrize("storage", ["ros1", "mcap"])
def test_calibration_from_camera_info(asl, tmp_path, storage):
    """Without --calib the bag's CameraInfo gives the same cameras, rig and rectified pixels."""
    suffix = ".bag" if storage == "ros1" else ""
    bag = write_bag(asl, tmp_path / f"info{suffix}", storage, "mono8", camera_info=True)
    folder = EurocSequence(asl)
    with RosbagSequence(bag, LEFT, RIGHT, None) as seq:
        for ours, theirs in ((seq.left_calibration, folder.left_calibration),
                             (seq.right_calibration, folder.right_calibration)):  # fmt: skip
            assert (ours.fx, ours.cy, ours.width, ours.distortion) == (
                theirs.fx, theirs.cy, theirs.width, theirs.distortion)  # fmt: skip
        T_right_left = invert_transform(seq.right_calibration.T_body_cam)  # body = left camera
        expected = invert_transform(folder.right_calibration.T_body_cam) @ (
            folder.left_calibration.T_body_cam
        )
        assert np.allclose(T_right_left, expected, atol=1e-9)
        assert seq.camera.baseline_m == pytest.approx(folder.camera.baseline_m, abs=1e-9)
        assert seq.camera.fx == pytest.approx(folder.camera.fx, abs=1e-6)
        for i in (0, FRAMES - 1):
            diff = seq[i].left.astype(int) - folder[i].left.astype(int)
            assert np.abs(diff).max() <= 1
    plain = write_bag(asl, tmp_path / f"plain{suffix}", storage, "mono8")
    with pytest.raises(DatasetError, match=r"no sensor_msgs/msg/CameraInfo '/cam0/camera_info'"):
        RosbagSequence(plain, LEFT, RIGHT, None)
