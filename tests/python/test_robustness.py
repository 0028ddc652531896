"""Bad input never crashes slslam, never ends in a traceback and is never accepted silently
(issue 17). Generated cases per family (hypothesis and tables): config numbers, YAML files,
sensor.yaml, trajectory files, command lines; plus `slslam run` interrupted by SIGINT / SIGTERM at
several moments. The count of generated cases is printed at the end of the module."""

from __future__ import annotations

import collections
import dataclasses
import json
import math
import os
import signal
import subprocess
import sys
import time
import typing
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from slslam.cli import main
from slslam.config import (
    Config,
    ConfigError,
    check_config,
    default_config,
    load_config,
    option_range,
)
from slslam.datasets import CameraCalibration
from slslam.datasets.trajectory_io import read_trajectory
from slslam.errors import CalibrationError, InputError, TrajectoryFileError

from conftest import camera_yaml

CASES: collections.Counter = collections.Counter()  # generated bad-input cases run, per family
SETTINGS = settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


def case_count_line() -> str:
    families = ", ".join(f"{k} {v}" for k, v in sorted(CASES.items()))
    return f"robustness: {sum(CASES.values())} generated bad-input cases ({families})"


def numeric_options() -> list[tuple[str, type, object]]:
    """(dotted key, int or float, range) of every numeric option of Config, walked from the
    dataclasses so that a new option is covered without editing this file."""
    found = []

    def walk(obj, prefix):
        hints = typing.get_type_hints(type(obj))
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if dataclasses.is_dataclass(value):
                walk(value, f"{prefix}{f.name}.")
                continue
            hint = hints[f.name]
            args = typing.get_args(hint) or (hint,)
            kinds = [a for a in args if a in (int, float)]
            if len(kinds) == 1 and bool not in args:
                found.append((prefix + f.name, kinds[0], option_range(type(obj), f)))

    walk(Config(), "")
    return found


NUMERIC = numeric_options()


def nested(key: str, value) -> dict:
    data = value
    for part in reversed(key.split(".")):
        data = {part: data}
    return data


def write_config(path: Path, key: str, value) -> Path:
    path.write_text(yaml.safe_dump(nested(key, value)))
    return path


#: Keys checked against another (min_window_s <= window_s): a valid value of one is written with
#: the other at a value the relation allows, so the table tests each key's own range.
RELATED = {
    "tracking.imu.window_s": ("min_window_s", min),
    "tracking.imu.min_window_s": ("window_s", max),
    # projected frames align patches of at least 5 x 5 (TrackerOptions::Check; XFeat's preset
    # projects)
    "tracking.track_refine_window_px": (
        "projected_max_frames",
        lambda window, projected: projected if window >= 2 else 0,
    ),
}


def write_valid_config(path: Path, key: str, value) -> Path:
    tree = nested(key, value)
    if key in RELATED:
        other, pick = RELATED[key]
        section, default = tree, Config()
        for part in key.split(".")[:-1]:
            section, default = section[part], getattr(default, part)
        section[other] = pick(value, getattr(default, other))
    path.write_text(yaml.safe_dump(tree))
    return path


def assert_one_line_error(exc: BaseException, path: Path | None, key: str | None = None):
    message = str(exc)
    assert "\n" not in message, message
    assert len(message) < 700, message  # a path, the key, the known keys at most
    if path is not None:
        assert str(path) in message
    if key is not None:
        assert key.split(".")[-1] in message


# ----------------------------------------------------------------------------------------------
# Config numbers


def test_every_numeric_option_declares_a_range():
    """New options need a range next to the field (``_option(default, "[lo, hi]")``) or in
    ``config.FOREIGN_RANGES``; the fallback only keeps numbers finite and inside C++ int."""
    assert len(NUMERIC) >= 20
    missing = [key for key, _, declared in NUMERIC if declared is None]
    assert not missing, f"options without a declared range: {missing}"
    for key, _, declared in NUMERIC:
        default = load_config(None)
        for part in key.split("."):
            default = getattr(default, part)
        if default is not None:
            assert default in declared, f"default of {key} ({default}) is outside {declared}"


ALWAYS_BAD = [math.nan, math.inf, -math.inf, 10**30, -(10**30), "three", [1, 2], {"a": 1}]


@pytest.mark.parametrize(("key", "kind", "declared"), NUMERIC, ids=[k for k, _, _ in NUMERIC])
def test_table_of_bad_numbers_for_every_option(tmp_path, key, kind, declared):
    """Every numeric key x {nan, +-inf, +-1e30, string, list, mapping, -1, 0, bounds +- 1}."""
    edge = [-1, 0, declared.low - 1, declared.high + 1, declared.low, declared.high]
    if kind is int:
        edge += [1.5, True]
    for value in ALWAYS_BAD + edge:
        CASES["config numbers"] += 1
        path = write_config(tmp_path / "c.yaml", key, value)
        valid = (
            not isinstance(value, (bool, str, list, dict))
            and (kind is float or isinstance(value, int))
            and value in declared
        )
        if valid:
            loaded = load_config(write_valid_config(tmp_path / "c.yaml", key, value))
            for part in key.split("."):
                loaded = getattr(loaded, part)
            assert loaded == value
            continue
        with pytest.raises(ConfigError) as info:
            load_config(path)
        assert_one_line_error(info.value, path, key)


@SETTINGS
@given(
    index=st.integers(0, len(NUMERIC) - 1),
    value=st.one_of(
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(-(10**40), 10**40),
        st.text(max_size=200),
        st.lists(st.integers(), max_size=3),
        st.booleans(),
        st.none(),
    ),
)
def test_generated_numbers_are_checked_or_kept(tmp_path, index, value):
    key, kind, declared = NUMERIC[index]
    CASES["config numbers"] += 1
    path = write_config(tmp_path / "g.yaml", key, value)
    try:
        loaded = load_config(path)
    except ConfigError as exc:
        assert_one_line_error(exc, path, key)
        return
    got = loaded
    for part in key.split("."):
        got = getattr(got, part)
    if value is None:  # optional options (max_keypoints) take null
        assert got is None
        return
    assert not isinstance(value, (bool, str, list))
    assert isinstance(got, kind) and math.isfinite(got) and got in declared


@SETTINGS
@given(
    index=st.integers(0, len(NUMERIC) - 1),
    fraction=st.floats(0, 1),
)
def test_accepted_values_pass_the_cpp_checks(index, fraction):
    """Python ranges are at least as strict as the C++ ``Check()``s: any accepted value builds."""
    from slslam import _core
    from slslam.datasets.euroc import RectifiedStereoCamera
    from slslam.features.orb import Orb
    from slslam.tracking.tracker import _core_options

    key, kind, declared = NUMERIC[index]
    span = min(declared.high, 1e5) - declared.low
    value = declared.low + fraction * span
    value = round(value) if kind is int else value
    if value not in declared:  # an open end: step inside it
        step = 1 if kind is int else 1e-6 * max(span, 1.0)
        value = declared.high - step if fraction > 0.5 else declared.low + step
    if kind is float and 0.0 < abs(value) < 1e-30:
        # (Python takes 1e-300 in an open (0, ...] range; the core stores many of these options
        # as float, where it is 0, and refuses it with its own clear error: config.Range)
        value = declared.low + 1e-6 * max(span, 1.0)
    config = load_config(None)
    section, name = key.rsplit(".", 1)
    parts = section.split(".")
    objs = [config]
    for part in parts:
        objs.append(getattr(objs[-1], part))
    changes = {name: value}
    if key in RELATED:  # the other key at a value the relation allows
        other, pick = RELATED[key]
        changes[other] = pick(value, getattr(objs[-1], other))
    new = dataclasses.replace(objs[-1], **changes)
    for part, parent in zip(reversed(parts), reversed(objs[:-1]), strict=True):
        new = dataclasses.replace(parent, **{part: new})
    check_config(new)
    camera = RectifiedStereoCamera(400.0, 400.0, 320.0, 240.0, 640, 480, 0.1, np.eye(4))
    _core_options(camera, new)
    Orb(new.features.orb)
    grid, dyn = _core.GridLimitOptions(), _core.DynamicCellOptions()
    grid.cell_size_px, grid.max_per_cell = (
        new.features.grid.cell_size_px,
        new.features.grid.max_per_cell,
    )
    d = new.features.dynamic_cells
    dyn.cell_size_px, dyn.sigma_px, dyn.alpha, dyn.threshold = (
        d.cell_size_px,
        d.sigma_px,
        d.alpha,
        d.threshold,
    )
    grid.check()
    dyn.check()


def test_values_set_in_code_are_checked_too():
    bad = dataclasses.replace(
        Config(), tracking=dataclasses.replace(Config().tracking, line_weight=math.nan)
    )
    with pytest.raises(ConfigError, match=r"tracking\.line_weight"):
        check_config(bad)


# ----------------------------------------------------------------------------------------------
# YAML files (configs and sensor.yaml share the reader)


def alias_bomb(levels: int = 9) -> str:
    lines = ['a0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for i in range(1, levels):
        refs = ", ".join([f"*a{i - 1}"] * 9)
        lines.append(f"a{i}: &a{i} [{refs}]")
    return "\n".join(lines) + "\n"


BAD_YAML = {
    "alias bomb": alias_bomb(),
    "one alias": "tracking: &t {line_weight: 1.0}\nother: *t\n",
    "huge file": "# " + "x" * (1 << 20) + "\n",
    "deep nesting": "tracking: " + "[" * 200 + "]" * 200 + "\n",
    "huge integer": "tracking:\n  local_keyframes: " + "9" * 5000 + "\n",
    "long string value": "tracking:\n  min_inliers: '" + "y" * 100_000 + "'\n",
    "unclosed bracket": "features: {grid: [}\n",
    "tab indentation": "tracking:\n\tline_weight: 1\n",
    "python tag": "tracking: !!python/object/apply:os.system ['true']\n",
    "top-level list": "- 1\n- 2\n",
    "top-level scalar": "42\n",
    "integer key": "tracking: {1: 2}\n",
    "null section": "tracking: null\n",
}


@pytest.mark.parametrize("name", list(BAD_YAML))
def test_bad_yaml_configs_fail_fast_with_one_line(tmp_path, name):
    CASES["yaml files"] += 1
    path = tmp_path / "bad.yaml"
    path.write_text(BAD_YAML[name])
    start = time.perf_counter()
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert time.perf_counter() - start < 2.0
    assert_one_line_error(info.value, path)
    assert "yyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyyy" not in str(info.value)


@SETTINGS
@given(data=st.binary(max_size=400))
def test_binary_garbage_configs(tmp_path, data):
    CASES["yaml files"] += 1
    path = tmp_path / "garbage.yaml"
    path.write_bytes(data)
    try:
        config = load_config(path)
    except ConfigError as exc:
        assert_one_line_error(exc, path)
    else:  # garbage that happens to be YAML holding nothing: the defaults
        assert config == default_config()


@SETTINGS
@given(text=st.text(max_size=300))
def test_text_garbage_configs(tmp_path, text):
    CASES["yaml files"] += 1
    path = tmp_path / "garbage.yaml"
    path.write_text(text, encoding="utf-8")
    try:
        config = load_config(path)
    except ConfigError as exc:
        assert_one_line_error(exc, path)
    else:
        assert config == default_config()


# ----------------------------------------------------------------------------------------------
# sensor.yaml


def sensor(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "sensor.yaml"
    path.write_text(text)
    return path


CAMERA_TABLE = {
    "resolution 200000 px": ("resolution: [64, 48]", "resolution: [200000, 200000]"),
    "resolution zero": ("resolution: [64, 48]", "resolution: [0, 48]"),
    "resolution fraction": ("resolution: [64, 48]", "resolution: [64.5, 48]"),
    "focal zero": ("intrinsics: [50.0, 50.0", "intrinsics: [0.0, 50.0"),
    "focal negative": ("intrinsics: [50.0, 50.0", "intrinsics: [50.0, -50.0"),
    "focal nan": ("intrinsics: [50.0", "intrinsics: [.nan"),
    "principal point far out": ("intrinsics: [50.0, 50.0, 31.5", "intrinsics: [50.0, 50.0, 1e6"),
    "k1 1e6": ("distortion_coefficients: [-0.05", "distortion_coefficients: [1000000.0"),
    "k2 -50": ("[-0.05, 0.01", "[-0.05, -50.0"),
    "p1 5": ("0.01, 0.0, 0.0]", "0.01, 5.0, 0.0]"),
    "k1 inf": ("distortion_coefficients: [-0.05", "distortion_coefficients: [.inf"),
    "k1 huge int": ("distortion_coefficients: [-0.05", "distortion_coefficients: [" + "9" * 400),
    "rate zero": ("rate_hz: 20", "rate_hz: 0"),
    "rate text": ("rate_hz: 20", "rate_hz: fast"),
    "alias": ("rate_hz: 20", "rate_hz: &r 20\nother: *r"),
}


@pytest.mark.parametrize("name", list(CAMERA_TABLE))
def test_camera_files_that_cannot_be_a_camera(tmp_path, name):
    CASES["sensor.yaml"] += 1
    old, new = CAMERA_TABLE[name]
    text = camera_yaml(0.0)
    assert old in text
    path = sensor(tmp_path, text.replace(old, new, 1))
    with pytest.raises(CalibrationError) as info:
        CameraCalibration.from_yaml(path)
    assert_one_line_error(info.value, path)


def test_a_40_mb_sensor_yaml_is_refused_at_once(tmp_path):
    CASES["sensor.yaml"] += 1
    path = sensor(tmp_path, camera_yaml(0.0) + "# " + "x" * (40 << 20) + "\n")
    start = time.perf_counter()
    with pytest.raises(CalibrationError, match="limited to"):
        CameraCalibration.from_yaml(path)
    assert time.perf_counter() - start < 1.0


@SETTINGS
@given(
    values=st.lists(
        st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-(10**9), 10**9)),
        min_size=4,
        max_size=4,
    )
)
def test_generated_intrinsics_and_distortion(tmp_path, values):
    CASES["sensor.yaml"] += 1
    text = camera_yaml(0.0)
    text = text.replace("intrinsics: [50.0, 50.0, 31.5, 23.5]", f"intrinsics: {values}")
    text = text.replace("[-0.05, 0.01, 0.0, 0.0]", f"{list(reversed(values))}")
    path = sensor(tmp_path, text.replace("nan", ".nan").replace("inf", ".inf"))
    try:
        cam = CameraCalibration.from_yaml(path)
    except CalibrationError as exc:
        assert_one_line_error(exc, path)
        return
    assert cam.fx > 0 and cam.fy > 0 and all(abs(k) <= 10 for k in cam.distortion)


def test_zero_baseline_and_int64_timestamps_name_the_file(make_euroc):
    from slslam.datasets import EurocSequence
    from slslam.errors import DatasetError

    root = make_euroc(n=3)
    right = root / "mav0" / "cam1" / "sensor.yaml"
    right.write_text(camera_yaml(0.0))  # cam1 on top of cam0
    with pytest.raises(DatasetError, match="baseline") as info:
        EurocSequence(root)
    assert str(right) in str(info.value)
    right.write_text(camera_yaml(-0.11))  # cam1 to the left
    with pytest.raises(DatasetError, match="right of cam0"):
        EurocSequence(root)
    right.write_text(camera_yaml(0.11))
    index = root / "mav0" / "cam0" / "data.csv"
    index.write_text(index.read_text().replace("1000000000,", "99999999999999999999999,", 1))
    with pytest.raises(DatasetError, match="int64") as info:
        EurocSequence(root)
    assert str(index) in str(info.value)
    CASES["sensor.yaml"] += 3


def test_12_bit_data_in_16_bit_pngs_is_scaled(make_euroc, caplog):
    from PIL import Image

    from slslam.datasets import EurocSequence

    root = make_euroc(n=2)
    sequence = EurocSequence(root, rectify=False)
    expected = sequence[0].left
    for cam in ("cam0", "cam1"):
        for png in (root / "mav0" / cam / "data").glob("*.png"):
            data = np.asarray(Image.open(png)).astype(np.uint16) * 16  # 12-bit values
            Image.fromarray(data).save(png)
    with caplog.at_level("INFO"):
        frame = EurocSequence(root, rectify=False)[0]
    assert np.array_equal(frame.left, expected)
    assert sum("12-bit" in r.getMessage() for r in caplog.records) == 1
    CASES["images"] += 1


# ----------------------------------------------------------------------------------------------
# Trajectory files

GOOD_ROWS = [f"{0.1 * i:.3f} {i} 0 0 0 0 0 1" for i in range(6)]


@SETTINGS
@given(
    row=st.integers(0, 5),
    column=st.integers(0, 7),
    token=st.sampled_from(["nan", "NaN", "inf", "-inf", "1e999", "-1e400"]),
)
def test_non_finite_trajectory_rows_are_named(tmp_path, row, column, token):
    CASES["trajectories"] += 1
    rows = [r.split() for r in GOOD_ROWS]
    rows[row][column] = token
    path = tmp_path / "t.tum"
    path.write_text("# t x y z qx qy qz qw\n" + "\n".join(" ".join(r) for r in rows) + "\n")
    with pytest.raises(TrajectoryFileError) as info:
        read_trajectory(path)
    assert f"line {row + 2}:" in str(info.value)
    assert_one_line_error(info.value, path)


@SETTINGS
@given(text=st.text(max_size=300))
def test_garbage_trajectories(tmp_path, text):
    CASES["trajectories"] += 1
    path = tmp_path / "g.tum"
    path.write_text(text, encoding="utf-8")
    try:
        traj = read_trajectory(path, "tum")
    except TrajectoryFileError as exc:
        assert_one_line_error(exc, path)
    else:
        assert np.all(np.isfinite(traj.positions_xyz))


# ----------------------------------------------------------------------------------------------
# Command lines


def run_cli(capsys, args: list[str]) -> tuple[int, str]:
    code = main([str(a) for a in args])
    captured = capsys.readouterr()
    return code, captured.out + captured.err


def assert_clean_failure(code: int, output: str) -> None:
    assert code != 0
    assert "Traceback" not in output
    errors = [line for line in output.splitlines() if line.startswith(("error:", "Error", "│"))]
    assert errors or "Invalid value" in output or "Usage" in output, output


@pytest.fixture
def small_sequence(make_euroc) -> Path:
    return make_euroc(n=3)


def cli_table(seq: Path, tmp: Path) -> dict[str, list]:
    afile = tmp / "a_file"
    afile.write_text("x")
    garbage = tmp / "garbage.tum"
    garbage.write_bytes(b"\x00\xff garbage \n nan nan")
    nan_gt = tmp / "nan.tum"
    nan_gt.write_text("\n".join(GOOD_ROWS[:3] + ["nan 1 0 0 0 0 0 1"]) + "\n")
    still = tmp / "still.tum"
    still.write_text("\n".join(f"{0.1 * i:.3f} 0 0 0 0 0 0 1" for i in range(20)) + "\n")
    bad_config = tmp / "bad.yaml"
    bad_config.write_text("tracking:\n  line_weight: .nan\n")
    return {
        "run --max-frames -3": ["run", seq, "--out", tmp / "o1", "--max-frames", "-3"],
        "rectify --frames -2": ["rectify", seq, "--out", tmp / "o2", "--frames", "-2"],
        "run --out file": ["run", seq, "--out", afile],
        "rectify --out file": ["rectify", seq, "--out", afile],
        "sim --out file": ["sim", "--out", afile, "--frames", "2"],
        "demo --out file": ["demo", "--out", afile],
        "eval --out file": ["eval", still, still, "--out", afile],
        "run nan config": ["run", seq, "--out", tmp / "o3", "--config", bad_config],
        "run missing config": ["run", seq, "--config", tmp / "none.yaml"],
        "run garbage gt": ["run", seq, "--out", tmp / "o4", "--groundtruth", garbage],
        "run nan gt": ["run", seq, "--out", tmp / "o5", "--groundtruth", nan_gt],
        "eval garbage": ["eval", garbage, still],
        "eval nan": ["eval", nan_gt, still],
        "eval stationary": ["eval", still, still, "--out", tmp / "o6"],
        "eval bad align": ["eval", still, still, "--align", "sim7"],
        "info missing": ["info", tmp / "nope"],
        "info a file": ["info", afile],
    }


def test_command_lines_fail_with_one_message(small_sequence, tmp_path, capsys):
    table = cli_table(small_sequence, tmp_path)
    for name, args in table.items():
        CASES["command lines"] += 1
        code, output = run_cli(capsys, args)
        assert code != 0, name
        assert_clean_failure(code, output)
    # the evaluation failure is recorded, not lost
    record = json.loads((tmp_path / "o6" / "metrics.json").read_text())
    assert "evaluation_error" in record
    # a bad ground truth fails before any frame is tracked
    assert not (tmp_path / "o4" / "trajectory.tum").exists()


def test_info_shows_a_broken_ground_truth_as_invalid(small_sequence, capsys):
    gt = small_sequence / "mav0" / "state_groundtruth_estimate0"
    gt.mkdir(parents=True)
    (gt / "data.csv").write_text("#t,x,y,z,qw,qx,qy,qz\n1000000000,nan,0,0,1,0,0,0\n")
    code, output = run_cli(capsys, ["info", small_sequence])
    assert code == 0 and "INVALID" in output and "line 2" in output
    CASES["command lines"] += 1


def test_the_command_line_in_a_subprocess_prints_no_traceback(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(alias_bomb())
    result = subprocess.run(
        [sys.executable, "-m", "slslam", "run", str(tmp_path), "--config", str(bad)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stderr.strip().count("\n") == 0 and "alias" in result.stderr
    CASES["command lines"] += 1


# ----------------------------------------------------------------------------------------------
# Signals


@pytest.fixture(scope="module")
def sim_sequence(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("sim") / "loop"
    subprocess.run(
        [sys.executable, "-m", "slslam", "sim", "--preset", "loop", "--frames", str(SIM_FRAMES)]
        + ["--out", str(out), "--no-lidar"],
        check=True,
        capture_output=True,
        timeout=300,
    )
    return out


SIM_FRAMES = 20


def start_run(sequence: Path, out: Path, pause_in: str | None = None) -> subprocess.Popen:
    env = dict(os.environ)
    env.pop("SLSLAM_TEST_PAUSE_IN", None)
    if pause_in:
        env["SLSLAM_TEST_PAUSE_IN"] = pause_in
    return subprocess.Popen(
        [sys.executable, "-m", "slslam", "run", str(sequence), "--out", str(out), "--orb"]
        + ["--no-lines", "--no-progress"],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def wait_for(condition, timeout: float = 120.0) -> None:
    end = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < end, "timed out"
        time.sleep(0.05)


def tracked_rows(out: Path) -> int:
    path = out / "trajectory.tum"
    return len(path.read_text().splitlines()) if path.exists() else 0


def finish(proc: subprocess.Popen) -> tuple[int, str]:
    _, err = proc.communicate(timeout=120)
    return proc.returncode, err


def check_outputs(out: Path, completed: bool) -> dict:
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["completed"] is completed
    traj = np.loadtxt(out / "trajectory.tum", ndmin=2)
    assert traj.shape[1] == 8 and np.all(np.isfinite(traj))
    if not completed:
        assert metrics["stopped_at_frame"] == metrics["frames"]
    assert not list(out.glob("*.partial"))
    if (out / "map.ply").exists():
        header, body = (out / "map.ply").read_text().split("end_header\n")
        vertices = int(header.split("element vertex ")[1].split()[0])
        edges = int(header.split("element edge ")[1].split()[0])
        assert len(body.splitlines()) == vertices + edges
    return metrics


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_early_in_tracking_keeps_the_rows_and_says_where(sim_sequence, tmp_path, signum):
    proc = start_run(sim_sequence, tmp_path)
    wait_for(lambda: tracked_rows(tmp_path) >= 2)
    proc.send_signal(signum)
    code, err = finish(proc)
    assert code == 128 + signum and "Traceback" not in err
    metrics = check_outputs(tmp_path, completed=False)
    assert metrics["stopped_in"] == "tracking"
    assert 2 <= metrics["frames"] < SIM_FRAMES and tracked_rows(tmp_path) == metrics["frames"]
    assert (tmp_path / "map.ply").exists()  # the first signal still writes the map


@pytest.mark.parametrize(("stage", "signum"), [("map", signal.SIGTERM), ("scoring", signal.SIGINT)])
def test_a_signal_after_tracking(sim_sequence, tmp_path, stage, signum):
    proc = start_run(sim_sequence, tmp_path, pause_in=stage)
    wait_for(lambda: (tmp_path / f"paused_in_{stage}").exists())
    proc.send_signal(signum)
    code, err = finish(proc)
    assert code == 128 + signum and "Traceback" not in err
    metrics = check_outputs(tmp_path, completed=False)
    assert metrics["stopped_in"] == stage and metrics["frames"] == SIM_FRAMES
    assert (tmp_path / "map.ply").exists() == (stage == "scoring")
    assert "ape" not in metrics


def test_a_second_signal_while_finishing(sim_sequence, tmp_path):
    proc = start_run(sim_sequence, tmp_path, pause_in="map")
    wait_for(lambda: tracked_rows(tmp_path) >= 2)
    proc.send_signal(signal.SIGINT)
    wait_for(lambda: (tmp_path / "paused_in_map").exists())
    proc.send_signal(signal.SIGTERM)
    code, err = finish(proc)
    assert code == 128 + signal.SIGTERM and "Traceback" not in err
    metrics = check_outputs(tmp_path, completed=False)
    assert metrics["stopped_in"] == "tracking" and metrics["finishing_stopped_in"] == "map"
    assert not (tmp_path / "map.ply").exists() and "ape" not in metrics


def test_an_uninterrupted_run_says_completed_and_scores_or_explains(sim_sequence, tmp_path):
    proc = start_run(sim_sequence, tmp_path)
    code, err = finish(proc)
    assert code == 0, err
    metrics = check_outputs(tmp_path, completed=True)
    assert "stopped_in" not in metrics
    assert "ape" in metrics or "evaluation_error" in metrics


def test_scoring_failures_are_recorded_not_raised(tmp_path):
    from evo.core.trajectory import PoseTrajectory3D

    from slslam.tracking.run import _score

    still = PoseTrajectory3D(poses_se3=[np.eye(4)] * 10, timestamps=np.arange(10.0))
    scores = _score(still, still, tmp_path)
    assert "evaluation_error" in scores and "\n" not in scores["evaluation_error"]
    short = PoseTrajectory3D(poses_se3=[np.eye(4)] * 2, timestamps=np.arange(2.0))
    assert "evaluation_error" in _score(short, still, tmp_path)
    assert not (tmp_path / "metrics.json").exists()  # only run_sequence writes it


# ----------------------------------------------------------------------------------------------
# C++ option structs through the bindings (the gtests in tests/cpp/tracking/options_check_test.cpp
# walk every field's range; here: every bound field reaches Python as InputError naming it)

#: (class, field): the non-finite or extreme values its range allows on purpose.
CPP_ALLOWED = {
    ("LinePreprocessOptions", "max_gap_px"): {math.inf, 1e30},  # inf: the paper's rule, no gap
    ("GridLimitOptions", "strong_score"): {math.inf, -math.inf, 1e30, -1e30},  # -inf: off
    ("OrbOptions", "denoise_above_noise"): {1e30, -1e30},  # <= 0: never; any finite level
}
#: Structs whose every field has a finite range (tests/cpp/tracking/options_check_test.cpp walks
#: them): +-1e30 and the extremes of int must fail too. In the others (LiDAR: "finite", ">= n")
#: a huge value is slow, not wrong, so only non-finite values and INT_MIN must fail.
CPP_BOUNDED = {
    "AssociationOptions",
    "BundleAdjustmentOptions",
    "DynamicCellOptions",
    "GridLimitOptions",
    "GuidedMatchOptions",
    "LineMatchOptions",
    "LinePreprocessOptions",
    "LocalMapperOptions",
    "MatchOptions",
    "OrbOptions",
    "PoseOptimizerOptions",
    "RelocalisationOptions",
    "StereoLineOptions",
    "StereoMatchOptions",
    "TrackerOptions",
    "VocabularyOptions",
}


#: The option structs this family walks (a new struct joins the list once its check() names its
#: fields and refuses non-finite values).
CPP_CHECKED = CPP_BOUNDED | {"RegistrationOptions"}


def cpp_option_fields() -> list[tuple[str, str, type]]:
    from slslam import _core

    fields = []
    for name in sorted(dir(_core)):
        cls = getattr(_core, name)
        if name not in CPP_CHECKED:
            continue
        obj = cls()
        for attr in sorted(dir(obj)):
            value = None if attr.startswith("_") else getattr(obj, attr)
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                fields.append((name, attr, type(value)))
    return fields


CPP_FIELDS = cpp_option_fields()


def test_every_cpp_option_struct_is_checked():
    from slslam import _core

    for name in sorted(CPP_CHECKED):
        if name == "RegistrationOptions" and not hasattr(_core, name):
            continue  # built without PCL
        assert hasattr(getattr(_core, name), "check"), name
    assert len(CPP_FIELDS) >= 100, len(CPP_FIELDS)


@pytest.mark.parametrize(
    ("cls_name", "field", "kind"), CPP_FIELDS, ids=[f"{c}.{f}" for c, f, _ in CPP_FIELDS]
)
def test_cpp_options_refuse_what_cannot_be_meant(cls_name, field, kind):
    """NaN, infinities, +-1e30 and the extremes of int fail check() with the project's error
    type naming the field, unless the field's documented range takes them."""
    from slslam import _core
    from slslam.errors import InputError

    cls = getattr(_core, cls_name)
    try:
        setattr(cls(), field, -1)
    except TypeError:  # an unsigned field (a seed): any value it holds is meant
        return
    bounded = cls_name in CPP_BOUNDED
    if kind is float:
        values = [math.nan, math.inf, -math.inf] + ([1e30, -1e30] if bounded else [])
    else:
        values = [-(2**31)] + ([2**31 - 1] if bounded else [])
    allowed = CPP_ALLOWED.get((cls_name, field), set())
    for value in values:
        obj = cls()
        if cls_name == "TrackerOptions":  # its default camera is empty: give it a valid one
            obj.rig = _core.StereoRig(
                _core.PinholeCamera(400.0, 400.0, 320.0, 240.0, 640, 480), 0.1
            )
        setattr(obj, field, value)
        CASES["C++ options"] += 1
        try:
            obj.check()
        except InputError as exc:
            message = str(exc)
            assert field in message, (cls_name, field, message)
            assert "\n" not in message and len(message) < 300
            continue
        assert value in allowed, f"{cls_name}.{field} = {value} accepted"


def test_cpp_failures_arrive_as_input_error():
    from slslam import _core
    from slslam.errors import InputError

    options = _core.TrackerOptions()
    options.rig = _core.StereoRig(_core.PinholeCamera(400.0, 400.0, 320.0, 240.0, 640, 480), 0.1)
    options.mapping.ba.line_weight = math.nan  # aborted the process inside Ceres before
    with pytest.raises(InputError, match=r"ba\.line_weight"):
        _core.TrackerCore(options, _core.LineExtractorOptions())
    with pytest.raises(InputError, match="baseline"):
        _core.StereoRig(_core.PinholeCamera(400.0, 400.0, 320.0, 240.0, 640, 480), 0.0)
    CASES["C++ options"] += 2


# ----------------------------------------------------------------------------------------------
# LiDAR files


def write_cloud(path: Path, xyz: np.ndarray, names=("x", "y", "z"), height: int = 1) -> Path:
    """A binary PCD or PLY of float32 rows with the given field names."""
    data = np.ascontiguousarray(xyz, dtype="<f4").tobytes()
    n = len(xyz)
    if path.suffix == ".pcd":
        header = (
            f"VERSION 0.7\nFIELDS {' '.join(names)}\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            f"WIDTH {n // height}\nHEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\n"
            "DATA binary\n"
        )
    else:
        header = f"ply\nformat binary_little_endian 1.0\nelement vertex {n}\n"
        header += "".join(f"property float {name}\n" for name in names) + "end_header\n"
    path.write_bytes(header.encode() + data)
    return path


@pytest.fixture
def lidar_module():
    import slslam.lidar

    if not slslam.lidar.available():
        pytest.skip("slslam._core was built without PCL")
    return slslam.lidar


@SETTINGS
@given(
    suffix=st.sampled_from([".pcd", ".ply"]),
    row=st.integers(0, 5),
    column=st.integers(0, 2),
    value=st.sampled_from([math.nan, math.inf, -math.inf]),
)
def test_non_finite_points_are_named(lidar_module, tmp_path, suffix, row, column, value):
    CASES["LiDAR files"] += 1
    xyz = np.arange(18, dtype=np.float32).reshape(6, 3)
    xyz[row, column] = value
    path = write_cloud(tmp_path / f"c{suffix}", xyz)
    with pytest.raises(InputError) as info:
        lidar_module.read_points(path)
    assert f"point {row} " in str(info.value)
    assert_one_line_error(info.value, path)


@pytest.mark.parametrize("suffix", [".pcd", ".ply"])
@pytest.mark.parametrize(
    "names", [("a", "y", "z"), ("x", "b", "z"), ("x", "y", "c"), ("X", "Y", "Z")]
)
def test_clouds_without_coordinates_are_refused(lidar_module, tmp_path, suffix, names):
    CASES["LiDAR files"] += 1
    path = write_cloud(tmp_path / f"c{suffix}", np.ones((4, 3)), names)
    missing = next(axis for axis in "xyz" if axis not in names)
    with pytest.raises(InputError, match=f"no '{missing}' field"):
        lidar_module.read_points(path)
    good = lidar_module.read_points(write_cloud(tmp_path / f"g{suffix}", np.ones((4, 3))))
    assert good.shape == (4, 4) and np.all(good[:, :3] == 1.0)


@pytest.mark.parametrize(
    ("options", "named"),
    [
        ({"fine_voxel_m": 1e-7}, "fine_voxel_m"),
        ({"fine_voxel_m": 1e-3, "coarse_voxel_m": 1e-3}, "coarse_voxel_m"),
        ({"fine_voxel_m": math.inf}, "fine_voxel_m"),
        ({"fine_voxel_m": math.nan}, "fine_voxel_m"),
    ],
)
def test_voxel_sizes_too_small_for_the_cloud(lidar_module, options, named):
    CASES["LiDAR files"] += 1
    cloud = np.random.default_rng(0).uniform(-20, 20, (3000, 3)).astype(np.float32)
    with pytest.raises(InputError, match=named) as info:
        lidar_module.register(cloud, cloud, min_range_m=0.0, **options)
    assert "_M_range_check" not in str(info.value)


def test_case_count_reaches_the_goal(capsys):
    """Last in the module: prints the count (visible without -s) and checks the goal."""
    with capsys.disabled():
        print(f"\n{case_count_line()}")
    if len(CASES) < 6:
        pytest.skip("only part of the module ran")
    assert sum(CASES.values()) >= 1000, CASES
