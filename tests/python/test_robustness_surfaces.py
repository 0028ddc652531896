"""Bad input on the surfaces of issue 63 gets a clear error, never a traceback, a hang or a silent
wrong answer; valid variations of the same inputs are accepted (0 valid input refused).

Generated cases per surface, each classified (see :class:`Tally`): ROS camera bags, LiDAR ASL
folders, LiDAR bags, vocabulary files, YAML configs, integer command-line options. Then the runs
that meet bad data or a signal in the middle: every output written so far stays valid. The
counts per surface are printed by the last test of the module.
"""

from __future__ import annotations

import collections
import importlib.util
import json
import math
import os
import signal
import struct
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from slslam.cli import main
from slslam.errors import InputError

from conftest import camera_yaml, ros_header, ros_imu_message

SETTINGS = settings(
    max_examples=110,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
#: fewer examples where one case writes and reads a whole bag (the suite stays near 2 minutes)
FEWER = settings(SETTINGS, max_examples=45)
HANG_S = 20  # a case that takes longer than this counts as a hang


class Tally:
    """Outcome counts per surface: ``error`` (a one-line InputError naming what it must),
    ``accepted`` (a valid case that loaded), and the failures ``traceback`` (any other
    exception), ``hang``, ``silent`` (bad input accepted), ``vague`` (an InputError that does not
    name the file / topic / key), ``refused`` (valid input refused)."""

    def __init__(self) -> None:
        self.counts: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)

    def line(self) -> str:
        rows = []
        for surface, c in sorted(self.counts.items()):
            failures = {k: c[k] for k in ("traceback", "hang", "silent", "vague", "refused")}
            rows.append(
                f"{surface}: {sum(c.values())} cases, {c['error']} clear errors, "
                f"{c['accepted']} accepted, " + ", ".join(f"{v} {k}" for k, v in failures.items())
            )
        return "\n".join(rows)


TALLY = Tally()


class _Hang(Exception):
    pass


@contextmanager
def hang_guard(seconds: int = HANG_S) -> Iterator[None]:
    """Raises _Hang when the block runs longer than ``seconds`` (SIGALRM; main thread only)."""

    def fire(signum, frame):
        raise _Hang()

    previous = signal.signal(signal.SIGALRM, fire)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def classify(
    surface: str, probe: Callable[[], object], valid: bool, must_name: tuple[str, ...] = ()
) -> str:
    """Runs ``probe`` and records and returns its outcome (see :class:`Tally`); asserts it is
    the right one: a valid case loads, a bad one raises a one-line InputError whose message
    holds every string of ``must_name``."""
    outcome, detail = "accepted", ""
    try:
        with hang_guard():
            probe()
    except _Hang:
        outcome = "hang"
    except InputError as exc:
        message = str(exc)
        detail = message
        named = all(part in message for part in must_name)
        one_line = "\n" not in message and len(message) < 800
        outcome = "refused" if valid else ("error" if named and one_line else "vague")
    except Exception as exc:  # anything else is a traceback for the user
        outcome, detail = "traceback", f"{type(exc).__name__}: {exc}"
    else:
        outcome = "accepted" if valid else "silent"
    TALLY.counts[surface][outcome] += 1
    expected = "accepted" if valid else "error"
    assert outcome == expected, f"{surface}: {outcome} ({detail[:400]}); must name {must_name}"
    return outcome


# ----------------------------------------------------------------------------------------------
# ROS camera bags

W, H = 32, 24
LEFT, RIGHT, IMU = "/cam0/image_raw", "/cam1/image_raw", "/imu0"
T0 = 1_000_000_000
FRAMES = 4


def typestore():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS1_NOETIC)


def image_message(ts, t_ns: int, image: np.ndarray, encoding: str = "mono8", **over):
    """A sensor_msgs/Image of ``image`` (uint8 or uint16, gray or 3 channels)."""
    channels = 1 if image.ndim == 2 else image.shape[2]
    fields = dict(
        header=ros_header(ts, t_ns),
        height=image.shape[0],
        width=image.shape[1],
        encoding=encoding,
        is_bigendian=0,
        step=image.shape[1] * channels * image.dtype.itemsize,
        data=np.frombuffer(np.ascontiguousarray(image).tobytes(), np.uint8),
    )
    fields.update(over)
    return ts.types["sensor_msgs/msg/Image"](**fields)


def compressed_message(ts, t_ns: int, data: bytes, fmt: str = "png"):
    return ts.types["sensor_msgs/msg/CompressedImage"](
        header=ros_header(ts, t_ns), format=fmt, data=np.frombuffer(data, np.uint8)
    )


class BagSpec:
    """The messages of a small stereo + IMU bag as raw bytes, to be corrupted before writing:
    ``messages`` holds [topic, msgtype, receive time, raw] in write order."""

    def __init__(self, kind: str = "mono8", seed: int = 0, imu: bool = True) -> None:
        import cv2

        ts = self.ts = typestore()
        rng = np.random.default_rng(seed)
        self.image_type = (
            "sensor_msgs/msg/CompressedImage" if kind == "png" else "sensor_msgs/msg/Image"
        )
        self.messages: list[list] = []
        self.imu = imu
        if imu:
            for i in range(20):
                t = T0 - 50_000_000 + 10_000_000 * i
                msg = ros_imu_message(ts, t, [0.01, 0.0, 0.0], [0.0, 0.0, 9.81])
                self.add(IMU, "sensor_msgs/msg/Imu", t, msg)
        for i in range(FRAMES):
            t = T0 + 50_000_000 * i
            for topic in (LEFT, RIGHT):
                gray = rng.integers(0, 255, (H, W), dtype=np.uint8)
                if kind == "png":
                    msg = compressed_message(ts, t, cv2.imencode(".png", gray)[1].tobytes())
                elif kind == "mono16":
                    msg = image_message(ts, t, gray.astype(np.uint16) * 257, "mono16")
                elif kind in ("bgr8", "rgb8"):
                    msg = image_message(ts, t, np.repeat(gray[:, :, None], 3, axis=2), kind)
                else:
                    msg = image_message(ts, t, gray)
                self.add(topic, self.image_type, t + 3_000_000, msg)

    def add(self, topic: str, msgtype: str, t_ns: int, msg) -> None:
        self.messages.append([topic, msgtype, t_ns, self.ts.serialize_ros1(msg, msgtype)])

    def index_of(self, topic: str, i: int) -> int:
        """Position in ``messages`` of message ``i`` of ``topic``."""
        return [k for k, m in enumerate(self.messages) if m[0] == topic][i]

    def replace(self, topic: str, i: int, msg=None, raw: bytes | None = None) -> None:
        k = self.index_of(topic, i)
        self.messages[k][3] = (
            raw if raw is not None else self.ts.serialize_ros1(msg, self.messages[k][1])
        )

    def write(self, path: Path) -> Path:
        from rosbags.rosbag1 import Writer

        with Writer(path) as writer:
            connections = {}
            for topic, msgtype, _, _ in self.messages:
                if topic not in connections:
                    connections[topic] = writer.add_connection(topic, msgtype, typestore=self.ts)
            for topic, _, t_ns, raw in self.messages:
                writer.write(connections[topic], t_ns, raw)
        return path


@pytest.fixture(scope="module")
def stereo_calib(tmp_path_factory) -> list[Path]:
    folder = tmp_path_factory.mktemp("calib")
    paths = []
    for name, x in (("cam0", 0.0), ("cam1", 0.11)):
        path = folder / f"{name}.yaml"
        path.write_text(camera_yaml(x, width=W, height=H))
        paths.append(path)
    return paths


def read_whole_bag(bag: Path, calib: list[Path], left: str = LEFT, right: str = RIGHT) -> None:
    """What a run reads: every stereo pair and the IMU."""
    from slslam.datasets.rosbag import RosbagSequence

    with RosbagSequence(
        bag, left, right, calib, imu_topic=IMU if IMU in _topics(bag) else None
    ) as seq:
        for frame in seq:
            assert frame.left.shape == (H, W) and frame.left.dtype == np.uint8
        if seq.imu_topic:
            samples = seq.imu()
            assert np.isfinite(samples["gyro"]).all()


def _topics(bag: Path) -> set[str]:
    from slslam.datasets.rosbag import bag_topics

    return {t.topic for t in bag_topics(bag)}


_bag_counter = iter(range(10**9))


def new_bag(tmp: Path) -> Path:
    return tmp / f"case{next(_bag_counter)}.bag"


IMAGE_DEFECTS = (
    "truncate",
    "garbage",
    "bad_encoding",
    "bad_step",
    "short_data",
    "long_data",
    "zero_width",
    "huge_size",
    "nanosec",
)


@SETTINGS
@given(
    defect=st.sampled_from(IMAGE_DEFECTS),
    side=st.sampled_from((LEFT, RIGHT)),
    index=st.integers(0, FRAMES - 1),
    fraction=st.floats(0.0, 0.999),
    noise=st.binary(min_size=0, max_size=600),
)
def test_bag_images_truncated_or_garbage(
    stereo_calib, tmp_path, defect, side, index, fraction, noise
):
    """One image message damaged: the error names the bag, the topic and the message index."""
    spec = BagSpec()
    ts = spec.ts
    t = T0 + 50_000_000 * index
    gray = np.zeros((H, W), np.uint8)
    raw = spec.messages[spec.index_of(side, index)][3]
    if defect == "truncate":
        spec.replace(side, index, raw=raw[: int(len(raw) * fraction)])
    elif defect == "garbage":
        spec.replace(side, index, raw=noise)
    elif defect == "bad_encoding":
        spec.replace(side, index, image_message(ts, t, gray, encoding=noise[:12].hex() or "x"))
    elif defect == "bad_step":
        step = W + 1 + int(fraction * 10_000)
        spec.replace(side, index, image_message(ts, t, gray, step=step))
    elif defect == "short_data":
        spec.replace(
            side, index, image_message(ts, t, gray[: max(0, int(H * fraction) - 1)], height=H)
        )
    elif defect == "long_data":
        spec.replace(
            side,
            index,
            image_message(ts, t, np.zeros((H + 1 + len(noise) % 5, W), np.uint8), height=H),
        )
    elif defect == "zero_width":
        spec.replace(side, index, image_message(ts, t, gray, width=0, step=0))
    elif defect == "huge_size":
        spec.replace(side, index, image_message(ts, t, gray, width=2**31 - 1, height=2**31 - 1))
    elif defect == "nanosec":
        msg = image_message(ts, t, gray)
        msg.header.stamp.nanosec = 10**9 + int(fraction * 10**9)
        spec.replace(side, index, msg)
    bag = spec.write(new_bag(tmp_path))
    classify(
        "ros camera bags",
        lambda: read_whole_bag(bag, stereo_calib),
        valid=False,
        must_name=(str(bag), side, f"message {index}"),
    )


@FEWER
@given(
    defect=st.sampled_from(("empty", "garbage", "truncated_png")),
    index=st.integers(0, FRAMES - 1),
    noise=st.binary(min_size=1, max_size=300),
    fraction=st.floats(0.05, 0.95),
)
def test_bag_compressed_images(stereo_calib, tmp_path, defect, index, noise, fraction):
    import cv2

    spec = BagSpec(kind="png")
    t = T0 + 50_000_000 * index
    if defect == "empty":
        data = b""
    elif defect == "garbage":
        data = b"\x89PNG" + noise if len(noise) % 2 else noise
    else:
        png = cv2.imencode(".png", np.full((H, W), 7, np.uint8))[1].tobytes()
        data = png[: int(len(png) * fraction)]
    spec.replace(LEFT, index, compressed_message(spec.ts, t, data))
    bag = spec.write(new_bag(tmp_path))
    classify(
        "ros camera bags",
        lambda: read_whole_bag(bag, stereo_calib),
        valid=False,
        must_name=(str(bag), LEFT, f"message {index}"),
    )


@FEWER
@given(
    defect=st.sampled_from(("truncate", "garbage", "nan", "huge", "repeat_stamp")),
    index=st.integers(1, 19),
    fraction=st.floats(0.0, 0.99),
    noise=st.binary(min_size=0, max_size=400),
    value=st.sampled_from((math.nan, math.inf, -math.inf, 1e30, -5e4)),
)
def test_bag_imu_messages(stereo_calib, tmp_path, defect, index, fraction, noise, value):
    spec = BagSpec()
    raw = spec.messages[spec.index_of(IMU, index)][3]
    t = T0 - 50_000_000 + 10_000_000 * index
    if defect == "truncate":
        spec.replace(IMU, index, raw=raw[: int(len(raw) * fraction)])
    elif defect == "garbage":
        spec.replace(IMU, index, raw=noise)
    elif defect in ("nan", "huge"):
        gyro = [value, 0.0, 0.0] if defect == "nan" else [0.0, 0.0, 0.0]
        acc = [0.0, 0.0, 9.81] if defect == "nan" else [0.0, value, 9.81]
        spec.replace(IMU, index, ros_imu_message(spec.ts, t, gyro, acc))
    else:
        spec.replace(IMU, index, ros_imu_message(spec.ts, t - 10_000_000, [0, 0, 0], [0, 0, 9.8]))
    bag = spec.write(new_bag(tmp_path))
    classify(
        "ros camera bags",
        lambda: read_whole_bag(bag, stereo_calib),
        valid=False,
        must_name=(str(bag), IMU, f"message {index}"),
    )


@SETTINGS
@given(
    defect=st.sampled_from(("same_topic", "zero_stamps", "repeat", "backwards")),
    index=st.integers(1, FRAMES - 1),
    side=st.sampled_from((LEFT, RIGHT)),
)
def test_bag_topics_and_stamps(stereo_calib, tmp_path, defect, index, side):
    """The same topic as left and right, stamps all zero, a stamp repeated or going back."""
    spec = BagSpec(imu=False)
    names: tuple[str, ...] = (side,)
    if defect == "zero_stamps":
        for topic in (LEFT, RIGHT):
            for i in range(FRAMES):
                spec.replace(topic, i, image_message(spec.ts, 0, np.zeros((H, W), np.uint8)))
        names = (LEFT, "zero")  # the first topic read is named
    elif defect in ("repeat", "backwards"):
        t = T0 + 50_000_000 * (index - 1) - (7 if defect == "backwards" else 0)
        spec.replace(side, index, image_message(spec.ts, t, np.zeros((H, W), np.uint8)))
        names = (side, f"message {index}")
    bag = spec.write(new_bag(tmp_path))
    left, right = (side, side) if defect == "same_topic" else (LEFT, RIGHT)
    classify(
        "ros camera bags",
        lambda: read_whole_bag(bag, stereo_calib, left, right),
        valid=False,
        must_name=(str(bag), *names),
    )


@FEWER
@given(
    offset=st.floats(0.3, 0.7),
    flips=st.lists(st.integers(0, 2000), min_size=1, max_size=8),
)
def test_bag_with_bytes_flipped_in_the_middle(stereo_calib, tmp_path, offset, flips):
    """Flipped bytes land in a record header, a message header or pixels: an error naming the
    bag, or (pixels, which a ROS1 bag has no checksum for) the bag reads as it is."""
    bag = BagSpec().write(new_bag(tmp_path))
    data = bytearray(bag.read_bytes())
    start = int(len(data) * offset)
    for f in flips:
        data[min(len(data) - 1, start + f)] ^= 0xFF
    bag.write_bytes(bytes(data))
    outcome = "accepted"
    try:
        with hang_guard():
            read_whole_bag(bag, stereo_calib)
    except _Hang:
        outcome = "hang"
    except InputError as exc:
        outcome = "error" if str(bag) in str(exc) and "\n" not in str(exc) else "vague"
    except Exception as exc:
        outcome = f"traceback {type(exc).__name__}: {exc}"
    TALLY.counts["ros camera bags"][outcome.split()[0]] += 1
    assert outcome in ("error", "accepted"), outcome


@FEWER
@given(
    kind=st.sampled_from(("mono8", "mono16", "bgr8", "rgb8", "png")),
    seed=st.integers(0, 2**32 - 1),
    imu=st.booleans(),
)
def test_valid_bags_are_accepted(stereo_calib, tmp_path, kind, seed, imu):
    bag = BagSpec(kind=kind, seed=seed, imu=imu).write(new_bag(tmp_path))
    classify("ros camera bags", lambda: read_whole_bag(bag, stereo_calib), valid=True)


@FEWER
@given(fraction=st.floats(0.0, 0.98), garbage=st.binary(max_size=64))
def test_bag_info_on_truncated_or_garbage_files(tmp_path, capsys, fraction, garbage):
    """`slslam info BAG` on a bag cut short or starting with garbage: one line naming the bag,
    or (a cut after the last record a reader needs) the topics it still holds."""
    bag = BagSpec().write(new_bag(tmp_path))
    data = bag.read_bytes()
    bag.write_bytes(
        garbage + data[len(garbage) :] if len(garbage) % 2 else data[: int(len(data) * fraction)]
    )
    with hang_guard():
        code = main(["info", str(bag)])
    out = capsys.readouterr()
    lines = [line for line in out.err.splitlines() if line.strip()]
    clear = code == 2 and len(lines) == 1 and str(bag) in lines[0] and "Traceback" not in out.err
    outcome = "accepted" if code == 0 else ("error" if clear else "vague")
    TALLY.counts["ros camera bags"][outcome] += 1
    assert outcome in ("error", "accepted"), out.err


def test_bag_run_finds_its_imu_or_runs_camera_only(stereo_calib, tmp_path):
    """`slslam run BAG` without --imu: the bag's only Imu topic, none (camera only), or a clear
    error when there are several."""
    from slslam.cli import _open_bag

    with_imu = BagSpec(imu=True).write(tmp_path / "imu.bag")
    without = BagSpec(imu=False).write(tmp_path / "noimu.bag")
    assert _open_bag(with_imu, LEFT, RIGHT, None, stereo_calib).imu_topic == IMU
    seq = _open_bag(without, LEFT, RIGHT, None, stereo_calib)
    assert seq.imu_topic is None and seq.has_imu is False
    spec = BagSpec(imu=True)
    for topic, msgtype, t, raw in list(spec.messages):
        if topic == IMU:
            spec.messages.append(["/imu1", msgtype, t, raw])
    two = spec.write(tmp_path / "two.bag")
    with pytest.raises(InputError, match=r"2 sensor_msgs/Imu topics.*--imu"):
        _open_bag(two, LEFT, RIGHT, None, stereo_calib)
    assert _open_bag(two, LEFT, RIGHT, "/imu1", stereo_calib).imu_topic == "/imu1"
    TALLY.counts["ros camera bags"]["accepted"] += 3
    TALLY.counts["ros camera bags"]["error"] += 1


# ----------------------------------------------------------------------------------------------
# LiDAR ASL folders (the simulator's layout), made by hand: 3 sweeps, IMU, ground truth

SWEEPS, POINTS, PERIOD_S = 3, 64, 0.1
LIDAR_T0 = 2_000_000_000

SENSOR_YAML = """sensor_type: lidar
T_BS:
  cols: 4
  rows: 4
  data: {T}
scan_period_s: {period}
"""
IMU_YAML = """sensor_type: imu
gyroscope_noise_density: 1.7e-4
gyroscope_random_walk: 1.9e-5
accelerometer_noise_density: 2.0e-3
accelerometer_random_walk: 3.0e-3
"""


def write_lidar_folder(root: Path, seed: int = 0) -> Path:
    """A valid LiDAR ASL folder under ``root`` (returned): every file a run reads."""
    rng = np.random.default_rng(seed)
    mav0 = root / "mav0"
    lidar0 = mav0 / "lidar0"
    for sub in ("data", "point_time"):
        (lidar0 / sub).mkdir(parents=True, exist_ok=True)
    rows = ["#timestamp [ns],filename"]
    for k in range(SWEEPS):
        t = LIDAR_T0 + int(PERIOD_S * 1e9) * k
        points = rng.uniform(-20, 20, (POINTS, 4)).astype(np.float32)
        points.tofile(lidar0 / "data" / f"{t}.bin")
        np.sort(rng.uniform(0, PERIOD_S, POINTS)).astype(np.float32).tofile(
            lidar0 / "point_time" / f"{t}.bin"
        )
        rows.append(f"{t},{t}.bin")
    (lidar0 / "data.csv").write_text("\n".join(rows) + "\n")
    (lidar0 / "sensor.yaml").write_text(
        SENSOR_YAML.format(T=json.dumps(np.eye(4).ravel().tolist()), period=PERIOD_S)
    )
    (mav0 / "imu0").mkdir(parents=True)
    t_imu = LIDAR_T0 - 50_000_000 + 5_000_000 * np.arange(80)
    imu = np.column_stack([t_imu, np.zeros((80, 3)), np.tile([0.0, 0.0, 9.81], (80, 1))])
    np.savetxt(mav0 / "imu0" / "data.csv", imu, delimiter=",", fmt=["%d"] + ["%.6f"] * 6)
    (mav0 / "imu0" / "sensor.yaml").write_text(IMU_YAML)
    gt_dir = mav0 / "state_groundtruth_estimate0"
    gt_dir.mkdir()
    gt = np.column_stack([t_imu, np.zeros((80, 3)), np.tile([1.0, 0, 0, 0], (80, 1))])
    np.savetxt(gt_dir / "data.csv", gt, delimiter=",", fmt=["%d"] + ["%.6f"] * 7)
    return root


def read_lidar_folder(root: Path) -> None:
    """What `slslam lidar run` reads before and while it runs: the index, then every sweep."""
    from slslam.lidar.datasets import open_lidar_sequence

    sequence = open_lidar_sequence(root)
    for sweep in sequence:
        assert np.isfinite(sweep.points).all()


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


_folder_counter = iter(range(10**9))


def new_folder(tmp: Path, seed: int = 0) -> Path:
    return write_lidar_folder(tmp / f"seq{next(_folder_counter)}", seed)


def set_sensor(root: Path, T: object = None, period: object = PERIOD_S, extra: str = "") -> Path:
    path = root / "mav0" / "lidar0" / "sensor.yaml"
    T = np.eye(4).ravel().tolist() if T is None else T
    path.write_text(SENSOR_YAML.format(T=json.dumps(T), period=period) + extra)
    return path


T_BS_DEFECTS = ("reflection", "bottom_row", "scaled", "bool", "short", "string", "nan", "far")


@SETTINGS
@given(
    defect=st.sampled_from(T_BS_DEFECTS),
    seed=st.integers(0, 2**32 - 1),
    amount=st.floats(0.01, 5.0),
)
def test_lidar_T_BS_that_is_no_rigid_transform(tmp_path, defect, seed, amount):
    rng = np.random.default_rng(seed)
    root = new_folder(tmp_path)
    T = np.eye(4)
    T[:3, :3] = random_rotation(rng)
    T[:3, 3] = rng.uniform(-1, 1, 3)
    values: list = T.ravel().tolist()
    if defect == "reflection":
        T[:3, :3] = T[:3, :3] @ np.diag([1.0, 1.0, -1.0])
        values = T.ravel().tolist()
    elif defect == "bottom_row":
        values[12 + int(rng.integers(0, 4))] += amount
    elif defect == "scaled":
        T[:3, :3] *= 1.0 + amount
        values = T.ravel().tolist()
    elif defect == "bool":
        values[int(rng.integers(0, 16))] = True
    elif defect == "short":
        values = values[: int(rng.integers(0, 16))]
    elif defect == "string":
        values[int(rng.integers(0, 16))] = "one"
    elif defect == "nan":
        values[int(rng.integers(0, 12))] = math.nan
    elif defect == "far":
        values[3] = 100.0 + 1e3 * amount
    path = set_sensor(
        root, [v if not isinstance(v, float) or math.isfinite(v) else None for v in values]
    )
    if defect == "nan":  # JSON has no NaN: YAML spells it .nan
        path.write_text(path.read_text().replace("null", ".nan"))
    classify("lidar folders", lambda: read_lidar_folder(root), False, (str(path), "T_BS"))


@FEWER
@given(seed=st.integers(0, 2**32 - 1), lever=st.floats(0.0, 5.0))
def test_lidar_proper_T_BS_is_accepted(tmp_path, seed, lever):
    rng = np.random.default_rng(seed)
    root = new_folder(tmp_path, seed)
    T = np.eye(4)
    T[:3, :3] = random_rotation(rng)
    T[:3, 3] = rng.normal(size=3) / math.sqrt(3) * lever
    set_sensor(root, [float(f"{v:.12f}") for v in T.ravel()])
    classify("lidar folders", lambda: read_lidar_folder(root), valid=True)


BAD_NUMBERS = (
    "true",
    "false",
    "0",
    "-0.1",
    "0.0001",
    "2",
    "1e400",
    "'0.1'",
    "[0.1]",
    "{}",
    ".nan",
    ".inf",
    "null",
    "ten",
)


@SETTINGS
@given(
    key=st.sampled_from(("scan_period_s", "rate_hz", "imu_noise")),
    bad=st.sampled_from(BAD_NUMBERS),
    noise_key=st.sampled_from(
        (
            "gyroscope_noise_density",
            "gyroscope_random_walk",
            "accelerometer_noise_density",
            "accelerometer_random_walk",
        )
    ),
)
def test_lidar_sensor_numbers(tmp_path, key, bad, noise_key):
    """scan_period_s, rate_hz and the IMU noise: a boolean, string, zero, NaN or out-of-range
    value is refused naming the file and key."""
    root = new_folder(tmp_path)
    if key == "scan_period_s":
        path = set_sensor(root, period=bad)
        valid = False  # none is in [1 ms, 1 s] (null: a key without a value)
    elif key == "rate_hz":
        path = root / "mav0" / "lidar0" / "sensor.yaml"
        text = SENSOR_YAML.format(T=json.dumps(np.eye(4).ravel().tolist()), period=0.1)
        text = text.replace("scan_period_s: 0.1\n", f"rate_hz: {bad}\n")
        path.write_text(text)
        valid = bad == "2"  # 2 Hz: a 0.5 s period, valid
    else:
        path = root / "mav0" / "imu0" / "sensor.yaml"
        path.write_text(IMU_YAML.replace(noise_key + ":", f"{noise_key}: {bad}\n#"))
        valid = bad in ("0", "0.0001", "2")  # in [0, 10]
    classify(
        "lidar folders",
        lambda: read_lidar_folder(root),
        valid,
        (str(path), key.split("_")[0] if key != "imu_noise" else noise_key),
    )


@FEWER
@given(
    sweep=st.integers(0, SWEEPS - 1),
    point=st.integers(0, POINTS - 1),
    value=st.one_of(
        st.floats(PERIOD_S * 1.5 + 1e-4, 1e9),
        st.floats(-1e9, -1e-6),
        st.sampled_from((math.nan, math.inf, -math.inf)),
    ),
)
def test_lidar_point_times_beyond_the_scan_period(tmp_path, sweep, point, value):
    root = new_folder(tmp_path)
    t = LIDAR_T0 + int(PERIOD_S * 1e9) * sweep
    path = root / "mav0" / "lidar0" / "point_time" / f"{t}.bin"
    times = np.fromfile(path, np.float32)
    times[point] = value
    if not (np.isfinite(times[point]) and 0 <= times[point] <= 1.5 * PERIOD_S):
        times.tofile(path)
        classify(
            "lidar folders", lambda: read_lidar_folder(root), False, (str(path), f"point {point}")
        )


@FEWER
@given(
    row=st.integers(0, 79),
    column=st.integers(0, 7),
    token=st.sampled_from(("nan", "inf", "-inf", "zeroquat", "bigquat", "1e30t", "-5t", "dup")),
)
def test_lidar_groundtruth_rows(tmp_path, row, column, token):
    root = new_folder(tmp_path)
    path = root / "mav0" / "state_groundtruth_estimate0" / "data.csv"
    table = np.loadtxt(path, delimiter=",")
    if token in ("nan", "inf", "-inf"):
        table[row, column] = float(token)
    elif token == "zeroquat":
        table[row, 4:8] = 0.0
    elif token == "bigquat":
        table[row, 4:8] *= 2.0
    elif token == "1e30t":
        table[row, 0] = 1e30
    elif token == "-5t":
        table[row, 0] = -5
    elif token == "dup":
        table[row, 0] = table[row - 1, 0] if row else table[1, 0]
    np.savetxt(path, table, delimiter=",", fmt="%.17g")
    classify("lidar folders", lambda: read_lidar_folder(root), False, (str(path), "row"))


DATA_CSV_DEFECTS = {
    "overflow": lambda rows: [f"{2**63 + 5},{rows[1].split(',')[1]}", *rows[2:]],
    "huge": lambda rows: [f"{'9' * 400},x.bin"],
    "negative": lambda rows: [f"-{rows[1]}"],
    "float": lambda rows: [rows[1].replace(",", ".5,", 1)],
    "one_column": lambda rows: [rows[1].split(",")[0]],
    "three_columns": lambda rows: [rows[1] + ",extra"],
    "traversal": lambda rows: [rows[1].split(",")[0] + ",../../sensor.yaml"],
    "empty_name": lambda rows: [rows[1].split(",")[0] + ","],
    "missing_file": lambda rows: [rows[1].split(",")[0] + ",nothere.bin"],
    "only_comments": lambda rows: ["# nothing"],
    "yaml_list": lambda rows: ["- a", "- b"],
    "repeated": lambda rows: [rows[1], rows[1]],
    "backwards": lambda rows: [rows[2], rows[1]],
}


@SETTINGS
@given(defect=st.sampled_from(sorted(DATA_CSV_DEFECTS)), garbage=st.binary(max_size=64))
def test_lidar_data_csv_rows(tmp_path, defect, garbage):
    root = new_folder(tmp_path)
    path = root / "mav0" / "lidar0" / "data.csv"
    rows = path.read_text().splitlines()
    path.write_text("\n".join(DATA_CSV_DEFECTS[defect](rows)) + "\n")
    must = (str(path),) if defect != "missing_file" else ("nothere.bin", "not found")
    classify("lidar folders", lambda: read_lidar_folder(root), False, must)


@FEWER
@given(data=st.binary(min_size=1, max_size=200))
def test_lidar_binary_garbage_index_and_yaml(tmp_path, data):
    root = new_folder(tmp_path)
    which = [
        "mav0/lidar0/data.csv",
        "mav0/lidar0/sensor.yaml",
        "mav0/imu0/data.csv",
        "mav0/imu0/sensor.yaml",
    ][len(data) % 4]
    path = root / which
    path.write_bytes(b"\xff\xfe" + data)
    classify("lidar folders", lambda: read_lidar_folder(root), False, (str(path),))


SENSOR_TEXT_DEFECTS = {
    "alias_bomb": 'a: &a ["x","x"]\nb: &b [*a,*a]\nc: &c [*b,*b]\nT_BS: {data: *c}\n',
    "duplicate": None,  # filled in the test: the valid file with scan_period_s twice
    "list": "- 1\n- 2\n",
    "scalar": "42\n",
    "no_T_BS": "scan_period_s: 0.1\n",
    "T_BS_list": "T_BS: [1, 2]\nscan_period_s: 0.1\n",
    "deep": "a: " + "[" * 200 + "]" * 200 + "\n",
}


@pytest.mark.parametrize("defect", sorted(SENSOR_TEXT_DEFECTS))
def test_lidar_sensor_yaml_text(tmp_path, defect):
    root = new_folder(tmp_path)
    path = root / "mav0" / "lidar0" / "sensor.yaml"
    text = SENSOR_TEXT_DEFECTS[defect]
    if text is None:
        text = path.read_text() + "scan_period_s: 0.2\n"
    path.write_text(text)
    classify("lidar folders", lambda: read_lidar_folder(root), False, (str(path),))


@SETTINGS
@given(
    defect=st.sampled_from(("odd_size", "empty", "nan", "far", "fifo", "folder", "point_count")),
    sweep=st.integers(0, SWEEPS - 1),
    cut=st.integers(1, 15),
)
def test_lidar_scan_files(tmp_path, defect, sweep, cut):
    root = new_folder(tmp_path)
    t = LIDAR_T0 + int(PERIOD_S * 1e9) * sweep
    path = root / "mav0" / "lidar0" / "data" / f"{t}.bin"
    points = np.fromfile(path, np.float32).reshape(-1, 4)
    must: tuple[str, ...] = (str(path),)
    if defect == "odd_size":
        path.write_bytes(points.tobytes()[:-cut])
    elif defect == "empty":
        path.write_bytes(b"")
    elif defect in ("nan", "far"):
        points[cut % POINTS, cut % 3] = np.nan if defect == "nan" else 1e5 * cut
        points.tofile(path)
    elif defect in ("fifo", "folder"):
        path.unlink()
        os.mkfifo(path) if defect == "fifo" else path.mkdir()
    elif defect == "point_count":
        points[: POINTS - cut].tofile(path)
        must = ("point times",)
    classify("lidar folders", lambda: read_lidar_folder(root), False, must)


@FEWER
@given(
    defect=st.sampled_from(("overflow", "nan", "backwards", "short_row", "text")),
    row=st.integers(1, 79),
)
def test_lidar_imu_csv(tmp_path, defect, row):
    root = new_folder(tmp_path)
    path = root / "mav0" / "imu0" / "data.csv"
    lines = path.read_text().splitlines()
    fields = lines[row].split(",")
    if defect == "overflow":
        fields[0] = "1e30"
    elif defect == "nan":
        fields[1 + row % 6] = "nan"
    elif defect == "backwards":
        fields[0] = lines[row - 1].split(",")[0]
    elif defect == "short_row":
        fields = fields[:3]
    else:
        fields[2] = "zero"
    lines[row] = ",".join(fields)
    path.write_text("\n".join(lines) + "\n")
    classify("lidar folders", lambda: read_lidar_folder(root), False, (str(path),))


@FEWER
@given(seed=st.integers(0, 2**32 - 1), period=st.floats(0.07, 1.0))
def test_lidar_valid_folders_are_accepted(tmp_path, seed, period):
    root = new_folder(tmp_path, seed)
    set_sensor(root, period=round(period, 6))
    classify("lidar folders", lambda: read_lidar_folder(root), valid=True)


# ----------------------------------------------------------------------------------------------
# LiDAR bags: PointCloud2 (x y z intensity float32, Ouster-style t uint32 ns) + Imu

CLOUD_TOPIC, CLOUD_POINTS = "/os/points", 50
CLOUD_RECORD = np.dtype(
    {"names": ["p", "t"], "formats": [("<f4", 4), "<u4"], "offsets": [0, 16], "itemsize": 20}
)


def cloud_message(ts, t_ns: int, rng: np.random.Generator, **over):
    T = ts.types
    Field = T["sensor_msgs/msg/PointField"]
    fields = [Field(name=n, offset=4 * i, datatype=7, count=1) for i, n in enumerate("xyz")]
    fields += [
        Field(name="intensity", offset=12, datatype=7, count=1),
        Field(name="t", offset=16, datatype=6, count=1),
    ]
    data = np.zeros(CLOUD_POINTS, dtype=CLOUD_RECORD)
    data["p"] = rng.uniform(-10, 10, (CLOUD_POINTS, 4))
    data["t"] = np.sort(rng.integers(0, 99_000_000, CLOUD_POINTS))
    values = dict(
        header=ros_header(ts, t_ns, "lidar"),
        height=1,
        width=CLOUD_POINTS,
        fields=fields,
        is_bigendian=False,
        point_step=20,
        row_step=20 * CLOUD_POINTS,
        data=data.view(np.uint8),
        is_dense=True,
    )
    values.update(over)
    return T["sensor_msgs/msg/PointCloud2"](**values)


class LidarBagSpec(BagSpec):
    """Three sweeps at 10 Hz and 20 IMU messages, as raw messages to corrupt."""

    def __init__(self, seed: int = 0) -> None:
        ts = self.ts = typestore()
        self.rng = np.random.default_rng(seed)
        self.messages = []
        for i in range(20):
            t = LIDAR_T0 - 20_000_000 + 20_000_000 * i
            self.add(IMU, "sensor_msgs/msg/Imu", t, ros_imu_message(ts, t, [0, 0, 0], [0, 0, 9.8]))
        for k in range(SWEEPS):
            t = LIDAR_T0 + 100_000_000 * k
            self.add(
                CLOUD_TOPIC, "sensor_msgs/msg/PointCloud2", t + 1000, cloud_message(ts, t, self.rng)
            )


def read_lidar_bag(bag: Path) -> None:
    from slslam.lidar.datasets import open_lidar_sequence

    sequence = open_lidar_sequence(bag)
    assert sequence.imu is not None
    for sweep in sequence:
        assert np.isfinite(sweep.points).all()


CLOUD_DEFECTS = (
    "truncate",
    "garbage",
    "short_data",
    "offset_past_step",
    "int_x",
    "time_far",
    "zero_points",
    "nan_all",
    "far_point",
    "repeat_stamp",
)


@FEWER
@given(
    defect=st.sampled_from(CLOUD_DEFECTS),
    index=st.integers(0, SWEEPS - 1),
    fraction=st.floats(0.0, 0.99),
    noise=st.binary(max_size=500),
)
def test_lidar_bag_clouds(tmp_path, defect, index, fraction, noise):
    spec = LidarBagSpec()
    ts, rng = spec.ts, spec.rng
    t = LIDAR_T0 + 100_000_000 * index
    raw = spec.messages[spec.index_of(CLOUD_TOPIC, index)][3]
    Field = ts.types["sensor_msgs/msg/PointField"]
    if defect == "truncate":
        spec.replace(CLOUD_TOPIC, index, raw=raw[: int(len(raw) * fraction)])
    elif defect == "garbage":
        spec.replace(CLOUD_TOPIC, index, raw=noise)
    elif defect == "short_data":
        spec.replace(
            CLOUD_TOPIC,
            index,
            cloud_message(ts, t, rng, width=CLOUD_POINTS + 1 + int(fraction * 1000)),
        )
    elif defect == "offset_past_step":
        fields = [Field(name=n, offset=4 * i, datatype=7, count=1) for i, n in enumerate("xyz")]
        fields[2] = Field(name="z", offset=17 + int(fraction * 100), datatype=7, count=1)
        spec.replace(CLOUD_TOPIC, index, cloud_message(ts, t, rng, fields=fields))
    elif defect == "int_x":
        fields = [
            Field(name=n, offset=4 * i, datatype=7 if n != "x" else 5, count=1)
            for i, n in enumerate("xyz")
        ]
        spec.replace(CLOUD_TOPIC, index, cloud_message(ts, t, rng, fields=fields))
    elif defect in ("time_far", "nan_all", "far_point"):
        msg = cloud_message(ts, t, rng)
        data = np.frombuffer(bytes(msg.data), CLOUD_RECORD).copy()
        if defect == "time_far":
            data["t"][int(fraction * CLOUD_POINTS)] = 160_000_000 + int(fraction * 4e9)
        elif defect == "nan_all":
            data["p"][:, 0] = np.nan
        else:
            data["p"][int(fraction * CLOUD_POINTS), 1] = 2e4 + 1e7 * fraction
        msg.data = data.view(np.uint8)
        spec.replace(CLOUD_TOPIC, index, msg)
    elif defect == "zero_points":
        spec.replace(CLOUD_TOPIC, index, cloud_message(ts, t, rng, width=0))
    elif defect == "repeat_stamp":
        index = max(index, 1)
        spec.replace(
            CLOUD_TOPIC, index, cloud_message(ts, LIDAR_T0 + 100_000_000 * (index - 1), rng)
        )
    bag = spec.write(new_bag(tmp_path))
    classify(
        "lidar bags",
        lambda: read_lidar_bag(bag),
        False,
        (str(bag), CLOUD_TOPIC, f"message {index}"),
    )


@FEWER
@given(
    defect=st.sampled_from(("truncate", "garbage", "nan")),
    index=st.integers(1, 19),
    fraction=st.floats(0.0, 0.99),
    noise=st.binary(max_size=300),
)
def test_lidar_bag_imu(tmp_path, defect, index, fraction, noise):
    spec = LidarBagSpec()
    raw = spec.messages[spec.index_of(IMU, index)][3]
    if defect == "truncate":
        spec.replace(IMU, index, raw=raw[: int(len(raw) * fraction)])
    elif defect == "garbage":
        spec.replace(IMU, index, raw=noise)
    else:
        t = LIDAR_T0 - 20_000_000 + 20_000_000 * index
        spec.replace(IMU, index, ros_imu_message(spec.ts, t, [0, math.nan, 0], [0, 0, 9.8]))
    bag = spec.write(new_bag(tmp_path))
    classify("lidar bags", lambda: read_lidar_bag(bag), False, (str(bag), IMU, f"message {index}"))


@settings(SETTINGS, max_examples=30)
@given(seed=st.integers(0, 2**32 - 1))
def test_lidar_valid_bags_are_accepted(tmp_path, seed):
    bag = LidarBagSpec(seed).write(new_bag(tmp_path))
    classify("lidar bags", lambda: read_lidar_bag(bag), valid=True)


# ----------------------------------------------------------------------------------------------
# Vocabulary files

FNV_OFFSET, FNV_PRIME = 0xCBF29CE484222325, 0x100000001B3


def fnv1a64(data: bytes) -> int:
    value = FNV_OFFSET
    for byte in data:
        value = ((value ^ byte) * FNV_PRIME) & 0xFFFFFFFFFFFFFFFF
    return value


def with_checksum(data: bytearray) -> bytes:
    data[-8:] = struct.pack("<Q", fnv1a64(bytes(data[:-8])))
    return bytes(data)


@pytest.fixture(scope="module")
def small_vocabulary(tmp_path_factory) -> Path:
    from slslam.place import Vocabulary, VocabularyOptions

    rng = np.random.default_rng(3)
    images = [rng.integers(0, 256, (120, 32), dtype=np.uint8) for _ in range(4)]
    path = tmp_path_factory.mktemp("vocab") / "small.slvoc"
    Vocabulary.train(images, VocabularyOptions(branching=3, levels=2)).save(path)
    return path


def word_weight_offsets(data: bytes) -> list[int]:
    """Byte offsets of the IDF weights of the word nodes (binary descriptors)."""
    cols, nodes = struct.unpack_from("<I", data, 16)[0], struct.unpack_from("<I", data, 28)[0]
    size = 16 + cols
    offsets = []
    for n in range(nodes):
        base = 32 + n * size
        if struct.unpack_from("<i", data, base + 4)[0] >= 0:
            offsets.append(base + 8)
    return offsets


def probe_vocabulary(path: Path) -> None:
    from slslam.place import Vocabulary

    vocabulary = Vocabulary.load(path)
    assert all(0 <= vocabulary.word_weight(w) <= 64 for w in range(vocabulary.num_words))


@SETTINGS
@given(
    word=st.integers(0, 8),
    weight=st.one_of(
        st.floats(64.0001, 1e308),
        st.floats(-1e308, -1e-9),
        st.sampled_from((math.nan, math.inf, -math.inf, 1e80)),
    ),
)
def test_vocabulary_weights_out_of_range(small_vocabulary, tmp_path, word, weight):
    data = bytearray(small_vocabulary.read_bytes())
    offsets = word_weight_offsets(data)
    struct.pack_into("<d", data, offsets[word % len(offsets)], weight)
    path = tmp_path / f"w{word}_{abs(hash(weight)) % 10**6}.slvoc"
    path.write_bytes(with_checksum(data))
    classify("vocabularies", lambda: probe_vocabulary(path), False, (str(path), "weight"))


@SETTINGS
@given(word=st.integers(0, 8), weight=st.floats(0.0, 64.0))
def test_vocabulary_weights_in_range_are_kept(small_vocabulary, tmp_path, word, weight):
    data = bytearray(small_vocabulary.read_bytes())
    offsets = word_weight_offsets(data)
    struct.pack_into("<d", data, offsets[word % len(offsets)], weight)
    path = tmp_path / f"ok{word}.slvoc"
    path.write_bytes(with_checksum(data))
    classify("vocabularies", lambda: probe_vocabulary(path), valid=True)


@SETTINGS
@given(
    defect=st.sampled_from(("flip", "truncate", "extend", "header")),
    where=st.floats(0.0, 0.999),
    value=st.integers(0, 2**32 - 1),
)
def test_vocabulary_damaged_files(small_vocabulary, tmp_path, defect, where, value):
    data = bytearray(small_vocabulary.read_bytes())
    if defect == "flip":
        data[int(where * len(data))] ^= 1 + value % 255
    elif defect == "truncate":
        data = data[: int(where * len(data))]
    elif defect == "extend":
        data += bytes([value % 256]) * (1 + value % 50)
    else:  # a header field changed, checksum fixed: the loader checks it against the nodes
        field = (8, 12, 16, 20, 24, 28)[int(where * 6)]
        if field == 20:  # branching below the tree's 3 children per node
            value %= 3
        elif field == 24:  # levels below the tree's depth 2, or beyond 64
            value = value % 2 if value % 3 else 65 + value % 1000
        elif struct.unpack_from("<I", data, field)[0] == value:
            value += 1
        struct.pack_into("<I", data, field, value % 2**32)
        data = bytearray(with_checksum(data))
    path = tmp_path / f"{defect}.slvoc"
    path.write_bytes(bytes(data))
    classify("vocabularies", lambda: probe_vocabulary(path), False, (str(path),))


@pytest.mark.parametrize("kind", ["fifo", "folder", "dev_zero", "dev_null", "missing", "empty"])
def test_vocab_info_on_special_files(tmp_path, capsys, kind):
    """`slslam vocab info` on a FIFO (would block), /dev/zero (endless), a folder: one line."""
    path = {"dev_zero": Path("/dev/zero"), "dev_null": Path("/dev/null")}.get(kind, tmp_path / "v")
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "folder":
        path.mkdir()
    elif kind == "empty":
        path.write_bytes(b"")
    with hang_guard():
        code = main(["vocab", "info", str(path)])
    out = capsys.readouterr()
    TALLY.counts["vocabularies"]["error" if code == 2 and str(path) in out.err else "vague"] += 1
    assert code == 2 and "Traceback" not in out.err
    assert str(path) in out.err and len(out.err.strip().splitlines()) == 1, out.err


# ----------------------------------------------------------------------------------------------
# Integer command-line options: out of range is a usage error (exit 2), never a traceback

INT_OPTIONS = [
    # (command, option, lowest accepted, highest accepted)
    (["vocab", "train", "IMAGES", "--out", "OUT"], "--seed", 0, 2**64 - 1),
    (["vocab", "train", "IMAGES", "--out", "OUT"], "--branching", 2, 10**8),
    (["vocab", "train", "IMAGES", "--out", "OUT"], "--levels", 1, 64),
    (["vocab", "train", "IMAGES", "--out", "OUT"], "--max-images", 0, 2**31 - 1),
    (["sim", "--out", "OUT"], "--frames", 1, 10**7),
    (["sim", "--out", "OUT"], "--laps", 1, 20),
    (["sim", "--out", "OUT"], "--seed", 0, 2**64 - 1),
    (["run", "DATASET", "--out", "OUT"], "--max-frames", 0, 2**63 - 1),
    (["rectify", "DATASET", "--out", "OUT"], "--frames", 0, 2**63 - 1),
    (["lidar", "run", "DATASET", "--out", "OUT"], "--max-sweeps", 2, None),
]


def command(template: list[str], tmp: Path) -> list[str]:
    names = {
        "IMAGES": str(tmp / "no_images"),
        "OUT": str(tmp / "out"),
        "DATASET": str(tmp / "no_dataset"),
    }
    return [names.get(a, a) for a in template]


@SETTINGS
@given(
    which=st.integers(0, len(INT_OPTIONS) - 1),
    below=st.booleans(),
    distance=st.one_of(st.integers(1, 10), st.integers(1, 2**70), st.just(10**400)),
)
def test_integer_options_out_of_range(tmp_path, capsys, which, below, distance):
    template, option, low, high = INT_OPTIONS[which]
    if high is None:
        below = True
    value = low - distance if below else high + distance
    code = main([*command(template, tmp_path), option, str(value)])
    out = capsys.readouterr()
    text = out.out + out.err
    clear = code == 2 and "Traceback" not in text and option in text
    TALLY.counts["cli integers"]["error" if clear else "vague"] += 1
    assert clear, text[-600:]
    assert not (tmp_path / "out").exists()


@FEWER
@given(which=st.integers(0, len(INT_OPTIONS) - 1), fraction=st.floats(0.0, 1.0))
def test_integer_options_in_range_pass_the_parser(tmp_path, capsys, which, fraction):
    """An in-range value passes to the command, which then fails on its missing input (a
    one-line error naming that input, not the option)."""
    template, option, low, high = INT_OPTIONS[which]
    high = 10**6 if high is None else high
    value = low + int(fraction * (high - low))
    # sim has no input to miss: an unknown --preset stops it after the options are parsed
    stop = ["--preset", "nowhere"] if template[0] == "sim" else []
    code = main([*command(template, tmp_path), option, str(value), *stop])
    out = capsys.readouterr()
    text = out.out + out.err
    accepted = code == 2 and "Invalid value" not in text and "Traceback" not in text
    TALLY.counts["cli integers"]["accepted" if accepted else "refused"] += 1
    assert accepted, text[-600:]


# ----------------------------------------------------------------------------------------------
# YAML configs: a key given twice, options that need another one, an empty provider list


def config_leaves() -> list[tuple[str, object]]:
    """(dotted key, default value) of every leaf option of the default config."""
    import dataclasses

    from slslam.config import Config

    found = []

    def walk(obj, prefix):
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if dataclasses.is_dataclass(value):
                walk(value, f"{prefix}{f.name}.")
            else:
                found.append((prefix + f.name, value))

    walk(Config(), "")
    return found


LEAVES = config_leaves()


def yaml_value(value) -> str:
    return json.dumps(list(value) if isinstance(value, tuple) else value)


def nested_text(key: str, leaf_lines: list[str]) -> str:
    """YAML text of ``key``'s sections with ``leaf_lines`` (``name: value``) in the innermost."""
    parts = key.split(".")
    lines = [f"{'  ' * i}{p}:" for i, p in enumerate(parts[:-1])]
    lines += [f"{'  ' * (len(parts) - 1)}{line}" for line in leaf_lines]
    return "\n".join(lines) + "\n"


@SETTINGS
@given(which=st.integers(0, len(LEAVES) - 1), same=st.booleans())
def test_config_key_given_twice(tmp_path, which, same):
    from slslam.config import load_config

    key, default = LEAVES[which]
    name = key.split(".")[-1]
    second = default if same else (not default if isinstance(default, bool) else default)
    path = tmp_path / f"twice{which}.yaml"
    path.write_text(
        nested_text(key, [f"{name}: {yaml_value(default)}", f"{name}: {yaml_value(second)}"])
    )
    classify("configs", lambda: load_config(path), False, (str(path), name, "twice"))


@SETTINGS
@given(picks=st.sets(st.integers(0, len(LEAVES) - 1), min_size=1, max_size=12))
def test_config_distinct_keys_are_accepted(tmp_path, picks):
    """The same name in two sections (grid.cell_size_px, dynamic_cells.cell_size_px) is no
    duplicate: random sets of keys at their defaults load."""
    from slslam.config import load_config

    tree: dict = {}
    for i in sorted(picks):
        key, default = LEAVES[i]
        section = tree
        for part in key.split(".")[:-1]:
            section = section.setdefault(part, {})
        section[key.split(".")[-1]] = list(default) if isinstance(default, tuple) else default
    path = tmp_path / "distinct.yaml"
    path.write_text(yaml.safe_dump(tree))
    classify("configs", lambda: load_config(path), valid=True)


@pytest.mark.parametrize(
    "text, names",
    [
        (
            "tracking:\n  local_ba_dogleg: true\n  local_ba_line_prior_weight: 0\n",
            ("local_ba_dogleg", "local_ba_line_prior_weight"),
        ),
        ("features:\n  xfeat:\n    providers: []\n", ("providers", "empty")),
        ("features:\n  superpoint:\n    providers: []\n", ("providers", "empty")),
    ],
)
def test_config_options_that_need_another(tmp_path, text, names):
    from slslam.config import load_config

    path = tmp_path / "needs.yaml"
    path.write_text(text)
    classify("configs", lambda: load_config(path), False, (str(path), *names))
    ok = tmp_path / "ok.yaml"
    ok.write_text(text.replace("0\n", "10\n").replace("[]", "[CPUExecutionProvider]"))
    classify("configs", lambda: load_config(ok), valid=True)


@pytest.mark.parametrize("target", ["folder", "unwritable_folder", "fifo"])
def test_rerun_and_save_map_outputs_checked_before_the_run(tmp_path, capsys, target):
    from slslam.sim import SimOptions  # noqa: F401  (the dataset below is never opened)

    path = tmp_path / "target"
    if target == "folder":
        path.mkdir()
    elif target == "fifo":
        os.mkfifo(path)
    else:
        (tmp_path / "locked").mkdir()
        (tmp_path / "locked").chmod(0o500)
        path = tmp_path / "locked" / "rec.rrd"
    for option in ("--rerun", "--save-map"):
        code = main(["run", str(tmp_path / "seq"), "--out", str(tmp_path / "o"), option, str(path)])
        err = capsys.readouterr().err
        if target == "unwritable_folder" and os.geteuid() == 0:
            continue  # root writes anywhere: nothing to refuse
        clear = code == 2 and option in err and str(path) in err and "Traceback" not in err
        TALLY.counts["cli outputs"]["error" if clear else "vague"] += 1
        assert clear, err


# Output targets of every command that writes files: a target that cannot be written is a
# one-line error naming it before any work; a writable one (odd characters included) passes.

HAS_TORCH = importlib.util.find_spec("torch") is not None
#: (command template, where the target goes, "file" or "folder" expected, what stops a valid case
#: right after the output check: a string its error names, or None where the command completes)
OUTPUT_COMMANDS = {
    "sim --out": (["sim", "--out", "TARGET", "--preset", "nowhere"], "folder", "nowhere"),
    "run --out": (["run", "DATASET", "--out", "TARGET"], "folder", "no_dataset"),
    "run --rerun": (["run", "DATASET", "--out", "OUT", "--rerun", "TARGET"], "file", "no_dataset"),
    "run --save-map": (
        ["run", "DATASET", "--out", "OUT", "--save-map", "TARGET"],
        "file",
        "no_dataset",
    ),
    "config --out": (["config", "--out", "TARGET"], "file", None),
    "models export": (["models", "export", "xfeat", "--out", "TARGET"], "file", "PyTorch"),
    "models quantize": (
        ["models", "quantize", "xfeat", "--out", "TARGET", "--images", "IMAGES"],
        "file",
        "no_images",
    ),
    "models convert": (["models", "convert", "WEIGHTS", "TARGET"], "file", "PyTorch"),
}
#: bad targets: a folder where a file goes, a file where a folder goes, a FIFO or device, a file
#: standing on the path, a folder nothing can be created in (root writes anywhere else), names
#: too long for the file system
BAD_TARGETS = [
    "folder",
    "file",
    "fifo",
    "dev_null",
    "under_file",
    "under_file_deep",
    "proc",
    "proc_deep",
    "long_name",
    "long_path",
]
GOOD_TARGETS = ["new", "new_subfolders", "existing"]
ODD_NAMES = [
    "plain",
    "with space",
    "Straße ñ 坑道",
    "-dash",
    "quote'and\"",
    "[bold red]x",
    "$HOME%20",
]
#: output targets whose check misses a kind of bad path (none left)
NOT_CHECKED_YET: dict[str, set[str]] = {}


def output_target(tmp: Path, kind: str, name: str, expects: str) -> Path:
    ext = "" if expects == "folder" else ".out"
    name = name + ext
    if kind in ("folder", "file", "fifo", "existing"):
        path = tmp / name
        if kind == "folder" or (kind == "existing" and expects == "folder"):
            path.mkdir()
        elif kind == "fifo":
            os.mkfifo(path)
        else:
            path.write_text("old\n")
        return path
    if kind == "dev_null":
        return Path("/dev/null")
    if kind.startswith("under_file"):
        (tmp / "a_file").write_text("x")
        return tmp / "a_file" / ("sub/" if kind == "under_file_deep" else "") / name
    if kind.startswith("proc"):
        return Path("/proc") / ("slslam_no_such/" if kind == "proc_deep" else "") / name
    if kind == "long_name":
        return tmp / ("n" * 300 + ext)
    if kind == "long_path":
        return tmp.joinpath(*["d" * 200] * 25, name)
    if kind == "new_subfolders":
        return tmp / "new" / name / name
    return tmp / name  # new


OUTPUT_CASES = [
    (cmd, kind, name)
    for cmd in OUTPUT_COMMANDS
    for kind in BAD_TARGETS + GOOD_TARGETS
    for name in (ODD_NAMES if kind in GOOD_TARGETS + ["folder", "file", "under_file"] else ["x"])
    if kind not in NOT_CHECKED_YET.get(cmd, ())
    and not (kind == "file" and OUTPUT_COMMANDS[cmd][1] == "file")  # a file is what it takes
    and not (kind == "folder" and OUTPUT_COMMANDS[cmd][1] == "folder")
]


@pytest.mark.parametrize(("cmd", "kind", "name"), OUTPUT_CASES)
def test_output_targets_checked_before_any_work(tmp_path, capsys, cmd, kind, name):
    template, expects, stop = OUTPUT_COMMANDS[cmd]
    valid = kind in GOOD_TARGETS
    if valid and cmd == "models export" and HAS_TORCH:
        pytest.skip("with PyTorch a valid target runs the whole export")
    target = output_target(tmp_path, kind, name, expects)
    (tmp_path / "weights.pth").write_bytes(b"not weights")
    names = {
        "TARGET": str(target),
        "OUT": str(tmp_path / "o"),
        "DATASET": str(tmp_path / "no_dataset"),
        "IMAGES": str(tmp_path / "no_images"),
        "WEIGHTS": str(tmp_path / "weights.pth"),
    }
    before = sorted(p.name for p in tmp_path.iterdir())
    with hang_guard():
        code = main([names.get(a, a) for a in template])
    out = capsys.readouterr()
    err = out.err
    lines = [line for line in err.splitlines() if line.startswith("error:")]
    if valid:
        if stop is None:  # the command completes: the file is written whole, no partial left
            ok = code == 0 and target.is_file() and yaml.safe_load(target.read_text()) is not None
        else:  # stopped by the input after the output check, the target not blamed
            ok = code == 2 and stop in err and len(lines) == 1 and "Traceback" not in err
        ok = (
            ok
            and not list(tmp_path.rglob("*partial*"))
            and not list(tmp_path.rglob(".slslam-probe*"))
        )
        TALLY.counts["cli outputs"]["accepted" if ok else "refused"] += 1
        assert ok, (code, err[-800:])
        return
    flat = err.replace("\n", "")  # rich may wrap a long path; soft_wrap keeps it one line
    named = str(target) in flat or str(target).replace("\\", "") in flat
    clear = code == 2 and len(lines) == 1 and named and "Traceback" not in err
    after = sorted(p.name for p in tmp_path.iterdir())
    clear = clear and after == before and not (stop is not None and stop in err)
    TALLY.counts["cli outputs"]["error" if clear else "vague"] += 1
    assert clear, (code, str(target)[:200], err[-800:], before, after)


def test_output_checks_refuse_what_root_could_not_write(tmp_path):
    """The checks try a probe file: root passes ``os.access`` even under /proc."""
    from slslam.files import check_output_folder, check_output_target

    for check in (check_output_target, check_output_folder):
        for path in (Path("/proc/x"), Path("/proc/none/x"), tmp_path / "n" / ("y" * 256)):
            with pytest.raises(InputError, match="--out"):
                check(path, "--out")
        check(tmp_path / "new" / "ok", "--out")
        assert not (tmp_path / "new").exists()  # nothing created by the check
    assert not list(tmp_path.rglob(".slslam-probe*"))


# ----------------------------------------------------------------------------------------------
# Bad data or a signal in the middle of a run: every output written so far stays valid


@pytest.fixture(scope="module")
def lidar_sim(tmp_path_factory) -> Path:
    """60 simulated sweeps with IMU and ground truth (the loop preset's first 6 s)."""
    from slslam.sim import SimOptions, Simulator

    out = tmp_path_factory.mktemp("lidar_sim")
    Simulator(SimOptions(preset="loop", frames=120, cameras=False)).write(out, progress=False)
    return out


def check_lidar_outputs(out: Path, completed: bool) -> dict:
    """metrics.json, the trajectories and map.ply are whole and agree with each other."""
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["completed"] is completed
    assert not list(out.glob("*.partial"))
    for name in ("trajectory.tum", "trajectory_odometry.tum"):
        rows = np.loadtxt(out / name, ndmin=2)
        assert rows.shape == (metrics["sweeps"], 8) and np.isfinite(rows).all()
    header, _, body = (out / "map.ply").read_bytes().partition(b"end_header\n")
    assert len(body) == 12 * int(header.split(b"element vertex ")[1].split()[0])
    assert (out / "trajectory.png").read_bytes()[:4] == b"\x89PNG"
    if not completed:
        assert metrics["stopped"]["after_sweeps"] == metrics["sweeps"]
    return metrics


def start_lidar_run(dataset: Path, out: Path) -> subprocess.Popen:
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "slslam",
            "lidar",
            "run",
            str(dataset),
            "--out",
            str(out),
            "--no-progress",
            "--no-loops",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def wait_until(condition: Callable[[], bool], timeout_s: float = 120.0) -> None:
    end = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < end, "timed out"
        time.sleep(0.02)


def started(out: Path) -> bool:
    """The run wrote its 'not completed yet' metrics.json: sweeps are being processed."""
    try:
        return json.loads((out / "metrics.json").read_text()).get("stopped_in") == "lidar"
    except (OSError, ValueError):
        return False


@pytest.mark.parametrize(
    "signals",
    [[signal.SIGINT], [signal.SIGTERM], [signal.SIGINT, signal.SIGTERM]],
    ids=["sigint", "sigterm", "twice"],
)
def test_lidar_run_stopped_by_a_signal_keeps_valid_outputs(lidar_sim, tmp_path, signals):
    """A signal mid-run: the sweeps so far are written whole (completed: false); a second one
    while the files are written does not cut them."""
    out = tmp_path / "out"
    proc = start_lidar_run(lidar_sim, out)
    wait_until(lambda: started(out) or proc.poll() is not None)
    time.sleep(0.3)
    for i, signum in enumerate(signals):
        proc.send_signal(signum)
        if i == 0 and len(signals) > 1:
            time.sleep(0.05)
    _, err = proc.communicate(timeout=120)
    assert "Traceback" not in err, err
    if proc.returncode == 0:  # finished before the signal came: complete outputs
        check_lidar_outputs(out, completed=True)
        pytest.skip("the run ended before the signal arrived")
    # both signals may come before the next sweep: the run stops on the last one received
    assert proc.returncode in [128 + s for s in signals], err
    metrics = check_lidar_outputs(out, completed=False)
    assert 0 < metrics["sweeps"] < 60
    assert signal.Signals(proc.returncode - 128).name in metrics["stopped"]["reason"]


def test_lidar_run_meeting_a_corrupt_sweep_keeps_the_sweeps_before(lidar_sim, tmp_path, capsys):
    import shutil

    seq = tmp_path / "seq"
    shutil.copytree(lidar_sim, seq)
    scans = sorted((seq / "mav0" / "lidar0" / "data").glob("*.bin"))
    scans[20].write_bytes(scans[20].read_bytes()[:-5])  # not a whole number of points
    out = tmp_path / "out"
    code = main(["lidar", "run", str(seq), "--out", str(out), "--no-progress", "--no-loops"])
    err = capsys.readouterr().err
    assert code == 2 and str(scans[20]) in err and "Traceback" not in err, err
    metrics = check_lidar_outputs(out, completed=False)
    assert metrics["sweeps"] == 20 and "16-byte points" in metrics["stopped"]["reason"]
    # a new run into the same folder: the stale files of the stopped one are gone
    code = main(["lidar", "run", str(seq), "--out", str(out), "--max-sweeps", "3", "--no-progress"])
    assert code == 0
    assert check_lidar_outputs(out, completed=True)["sweeps"] == 3


def test_lidar_run_deskewed_metric_says_what_was_done(lidar_sim, tmp_path):
    for flags, deskewed in (([], True), (["--no-deskew"], False)):
        out = tmp_path / ("d" if deskewed else "n")
        args = ["lidar", "run", str(lidar_sim), "--out", str(out), "--max-sweeps", "4"]
        assert main([*args, "--no-progress", *flags]) == 0
        metrics = check_lidar_outputs(out, completed=True)
        assert metrics["deskewed"] is deskewed
        assert metrics["deskewed_sweeps"] == (4 if deskewed else 0)


def test_lidar_run_of_two_sweeps_says_why_it_has_no_ape(lidar_sim, tmp_path, capsys):
    out = tmp_path / "two"
    args = ["lidar", "run", str(lidar_sim), "--out", str(out), "--max-sweeps", "2"]
    assert main([*args, "--no-progress"]) == 0
    assert "APE needs at least 3 sweeps" in capsys.readouterr().out
    assert "at least 3 sweeps" in check_lidar_outputs(out, completed=True)["evaluation_error"]


@pytest.fixture(scope="module")
def vocab_images(tmp_path_factory) -> Path:
    from slslam import _core

    folder = tmp_path_factory.mktemp("vocab_images")
    rng = np.random.default_rng(5)
    for i in range(80):
        image = (rng.random((240, 320)) * 255).astype(np.uint8)
        _core.write_image(str(folder / f"{i:03d}.png"), image)
    return folder


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("after_s", [0.5, 3.0])
def test_vocab_train_stopped_by_a_signal_writes_nothing_or_all(
    vocab_images, tmp_path, signum, after_s
):
    """A signal while descriptors are extracted or the tree is trained: exit 128 + signum with
    no file (or the previous one untouched) and no .partial; the command never dies half-way."""
    from slslam.place import Vocabulary

    out = tmp_path / "v.slvoc"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "slslam",
            "vocab",
            "train",
            str(vocab_images),
            "--out",
            str(out),
            "--no-progress",
            "--levels",
            "5",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(after_s)  # 0: while the modules load; 1.5: extracting or training
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    assert "Traceback" not in err, err
    assert not list(tmp_path.glob("*.partial"))
    if proc.returncode == 0:
        Vocabulary.load(out)  # finished first: the file is whole
        pytest.skip("training ended before the signal arrived")
    if proc.returncode == -signum:
        # The default action: before Python's handlers exist (nothing written), or after they
        # are gone at the interpreter's exit (the file already written whole, atomically).
        assert not out.exists() or Vocabulary.load(out).num_words > 0
        return
    assert proc.returncode == 128 + signum, err
    assert "stopped" in err and (not out.exists() or Vocabulary.load(out).num_words > 0)


def test_a_signal_landing_where_python_cannot_raise_still_stops_without_a_traceback():
    """The handler's KeyboardInterrupt raised inside a __del__ (as inside importlib's module-lock
    callbacks while modules load) is swallowed by the interpreter with an "Exception ignored"
    traceback: the CLI's handlers send the signal again, so the stop still happens, silently."""
    script = textwrap.dedent(
        """
        import signal, time
        from slslam.cli import _signals_outside_commands

        class Dropped:
            def __del__(self):
                signal.raise_signal(signal.SIGINT)
                for _ in range(1000):  # the handler runs in here
                    pass

        received = []
        try:
            with _signals_outside_commands(received):
                Dropped()
                time.sleep(5)
            print("not stopped")
        except KeyboardInterrupt:
            print("stopped", sorted(set(received)))
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr, done.stderr
    assert done.stdout.split() == ["stopped", "[2]"], done.stdout


@pytest.fixture(scope="module")
def camera_sim(tmp_path_factory) -> Path:
    from slslam.sim import SimOptions, Simulator

    out = tmp_path_factory.mktemp("camera_sim") / "seq"
    Simulator(SimOptions(preset="loop", frames=16, lidar=False)).write(out, progress=False)
    return out


def test_bag_run_meeting_a_corrupt_frame_keeps_the_frames_before(camera_sim, tmp_path, capsys):
    """`slslam run BAG` (no --imu: the bag's one Imu topic is found) whose left image 10 has
    too few bytes: exit 2 naming the bag, topic and message; the 10 frames before are written.
    (A message that does not even decode is refused when the bag is indexed, before any output.)"""
    from slslam.datasets import EurocSequence

    seq = EurocSequence(camera_sim, rectify=False)
    ts = typestore()
    spec = BagSpec.__new__(BagSpec)
    spec.ts, spec.messages = ts, []
    imu = seq.imu()
    for t, w, a in zip(imu["t_ns"], imu["gyro"], imu["acc"], strict=True):
        spec.add(IMU, "sensor_msgs/msg/Imu", int(t), ros_imu_message(ts, int(t), w, a))
    for frame in seq:
        for topic, image in ((LEFT, frame.left), (RIGHT, frame.right)):
            spec.add(
                topic,
                "sensor_msgs/msg/Image",
                frame.t_ns + 1000,
                image_message(ts, frame.t_ns, image),
            )
    # decodes as a message (so the bag opens), but its pixels are 100 bytes short
    frame = seq[10]
    short = image_message(ts, frame.t_ns, frame.left)
    short.data = short.data[:-100]
    spec.replace(LEFT, 10, short)
    bag = spec.write(tmp_path / "corrupt.bag")
    out = tmp_path / "out"
    calib = camera_sim / "mav0"
    code = main(
        [
            "run",
            str(bag),
            "--left",
            LEFT,
            "--right",
            RIGHT,
            "--calib",
            str(calib),
            "--out",
            str(out),
            "--orb",
            "--no-lines",
            "--no-progress",
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err, err
    assert str(bag) in err and f"{LEFT} message 10" in err, err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["completed"] is False and metrics["stopped_at_frame"] == 10
    assert len((out / "frames.csv").read_text().splitlines()) == 1 + 10  # header + 10 frames
    assert len(np.loadtxt(out / "trajectory.tum", ndmin=2)) <= 10
    assert not list(out.glob("*.partial"))


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_rectify_stopped_by_a_signal_leaves_only_whole_images(camera_sim, tmp_path, signum):
    import cv2

    out = tmp_path / "rect"
    proc = subprocess.Popen(
        [sys.executable, "-m", "slslam", "rectify", str(camera_sim), "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    wait_until(lambda: (out / "left").is_dir() or proc.poll() is not None)
    time.sleep(0.2)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    assert "Traceback" not in err, err
    assert proc.returncode in (0, 128 + signum, -signum), err
    assert not list(out.rglob("*partial*"))
    for png in out.rglob("*.png"):
        assert cv2.imread(str(png), cv2.IMREAD_UNCHANGED) is not None, png


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_sim_stopped_by_a_signal_leaves_a_valid_sequence(tmp_path, signum):
    """A signal while `slslam sim` writes: it stops between frames with one line (exit 128 +
    signum); the folder reads as a EuRoC sequence of every frame its index lists, whole, and the
    manifest says interrupted and how many."""
    import cv2

    from slslam.datasets import EurocSequence

    out = tmp_path / "seq"
    proc = subprocess.Popen(
        [sys.executable, "-m", "slslam", "-q", "sim", "--frames", "40", "--no-lidar"]
        + ["--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)},
    )
    index = out / "mav0" / "cam0" / "data.csv"

    def frames_appeared() -> bool:
        try:
            return len(index.read_text().splitlines()) >= 3  # header + 2 frames
        except OSError:
            return False

    wait_until(lambda: frames_appeared() or proc.poll() is not None)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    assert "Traceback" not in err, err
    assert not list(out.rglob("*partial*"))
    manifest = json.loads((out / "manifest.json").read_text())
    if proc.returncode == 0:
        assert manifest["status"] == "complete"
        pytest.skip("the simulation ended before the signal arrived")
    assert proc.returncode == 128 + signum, err
    stopped = [line for line in err.splitlines() if line.startswith("stopped:")]
    assert len(stopped) == 1 and signal.Signals(signum).name in stopped[0], err
    assert manifest["status"] == "interrupted" and 2 <= manifest["frames_written"] < 40
    seq = EurocSequence(out, rectify=False)
    assert len(seq) == manifest["frames_written"]
    for cam in ("cam0", "cam1"):
        rows = (out / "mav0" / cam / "data.csv").read_text().splitlines()[1:]
        assert len(rows) == manifest["frames_written"]
        for row in rows:
            png = out / "mav0" / cam / "data" / row.split(",")[1]
            assert cv2.imread(str(png), cv2.IMREAD_UNCHANGED) is not None, png
    for frame in seq:
        assert frame.left is not None and frame.right is not None


def test_sim_signal_before_any_frame_writes_nothing(tmp_path):
    """``between_frames`` raising before the first frame: nothing under the final name."""
    from slslam.sim import SimOptions, Simulator
    from slslam.tracking.run import RunInterrupted

    def stop():
        raise RunInterrupted(signal.SIGTERM)

    sim = Simulator(SimOptions(preset="straight", frames=3, lidar=False))
    with pytest.raises(RunInterrupted):
        sim.write(tmp_path / "seq", progress=False, between_frames=stop)
    assert not (tmp_path / "seq").exists()


def test_case_counts_per_surface(capsys):
    """Last in the module: prints the counts per surface (visible without -s)."""
    with capsys.disabled():
        print("\n" + TALLY.line())
    failures = {
        s: {k: c[k] for k in ("traceback", "hang", "silent", "vague", "refused") if c[k]}
        for s, c in TALLY.counts.items()
    }
    assert not any(failures.values()), failures
    if len(TALLY.counts) < 6:
        pytest.skip("only part of the module ran")
    for surface in (
        "ros camera bags",
        "lidar folders",
        "lidar bags",
        "vocabularies",
        "cli integers",
        "configs",
        "cli outputs",
    ):
        assert sum(TALLY.counts[surface].values()) >= 100, (surface, TALLY.counts[surface])
