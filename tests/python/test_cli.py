import json
import subprocess
import sys

import pytest

import slslam
from slslam import _core
from slslam.cli import main


def test_version_is_single_sourced():
    assert slslam.__version__ == _core.__version__


def test_help_lists_every_subcommand():
    result = subprocess.run(
        [sys.executable, "-m", "slslam", "--help"], capture_output=True, text=True, check=True
    )
    for command in ("eval", "info", "rectify", "demo", "config", "version"):
        assert command in result.stdout


def test_demo_writes_files_a_user_can_open(tmp_path):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    # The synthetic estimate drifts 0.02 deg/m with 1 cm noise: error of centimetres to
    # decimetres after SE3 alignment, never zero, never metres.
    assert 0.02 < metrics["ape"]["rmse"] < 0.5
    assert metrics["rpe"]["rmse"] > 0
    for name in ("groundtruth.tum", "estimate.tum", "ape.png"):
        assert (out / name).stat().st_size > 0


def test_info_and_rectify_on_a_small_sequence(make_euroc, tmp_path, capsys):
    root = make_euroc(n=3)
    assert main(["info", str(root)]) == 0
    assert "stereo pairs     3" in capsys.readouterr().out
    out = tmp_path / "rect"
    assert main(["rectify", str(root), "--out", str(out), "--frames", "2"]) == 0
    assert len(list((out / "left").glob("*.png"))) == 2
    assert len(list((out / "right").glob("*.png"))) == 2


@pytest.mark.parametrize("args", [["info", "/no/such/dataset"], ["rectify", "/tmp", "--out", "x"]])
def test_bad_dataset_paths_give_one_error_line(args, capsys):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and "Traceback" not in err


def test_usage_error_exit_code():
    assert main(["eval"]) == 2


def test_config_prints_what_run_uses_and_loads_back(tmp_path, capsys):
    """`slslam config` prints every key with the front end's preset under the file's keys; its
    output loads as a config giving the same configuration (--orb: ORB's preset)."""
    from slslam.config import default_config, load_config

    assert main(["config"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("# slslam ") and "point_frontend: orb" in text
    printed = tmp_path / "printed.yaml"
    printed.write_text(text)
    assert load_config(printed) == default_config()
    mine = tmp_path / "mine.yaml"
    mine.write_text("tracking:\n  keyframe_min_frames: 4\n")
    out = tmp_path / "effective.yaml"
    assert main(["config", "--config", str(mine), "--orb", "--out", str(out)]) == 0
    effective = load_config(out)
    assert effective.features.point_frontend == "orb"
    assert effective.tracking.keyframe_min_frames == 4  # the file's key
    assert effective.tracking.stereo_row_search  # ORB's preset
    assert effective == load_config(mine, point_frontend="orb")
    assert main(["config", "--xfeat", "--out", str(out)]) == 0
    assert load_config(out) == default_config("xfeat")
    assert main(["config", "--orb", "--xfeat"]) == 2  # one front end, not both
    assert main(["config", "--config", str(tmp_path / "missing.yaml")]) == 2


def test_help_paragraphs_reflow_and_output_stays_one_line_in_a_log():
    """A command's help reflows its docstring's paragraphs to the terminal's width (no break
    left where the source line ended), and what a command prints to a file or a pipe is one
    line per message, however narrow the terminal would be."""
    import os

    env = dict(os.environ, COLUMNS="70")
    help_text = subprocess.run(
        [sys.executable, "-m", "slslam", "lidar", "run", "--help"],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    ).stdout
    flat = " ".join(line.strip(" │") for line in help_text.splitlines())
    # the docstring breaks after "voxel" and after "the simulator's": reflowed, neither is a
    # line end any more, and the sentence reads through
    assert "a bounded voxel map from the IMU prediction" in flat
    ends = [line.rstrip().rsplit(" ", 1)[-1] for line in help_text.splitlines() if line.strip()]
    assert "voxel" not in ends and "simulator's" not in ends
    version = subprocess.run(
        [sys.executable, "-m", "slslam", "version"], capture_output=True, text=True, env=env
    ).stdout
    assert len(version.strip().splitlines()) == 1

    from slslam.terminal import reflow

    assert (
        reflow("a\nb\n\n- x\n- y\n\n    code\n    here") == "a b\n\n- x\n- y\n\n    code\n    here"
    )
