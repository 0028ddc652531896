"""slslam bench: spec errors, content keys, marked blocks, and sweeps inline and on Ray.

The Ray tests run benchmarks/specs/smoke.yaml (2 configurations x 2 seeds of a 30-frame simulated
loop) on Ray's local mode with 2 workers and inline, in one Ray session for the module (its own
temporary folder, so parallel test processes do not share one).
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import tempfile
from pathlib import Path

import pytest

try:
    import ray
except ImportError:  # the Ray tests skip; the rest run
    ray = None

from slslam.bench import load_spec, run_bench
from slslam.bench.blocks import replace_block, update_file
from slslam.bench.cells import plan_cells
from slslam.bench.results import compare_results, write_results
from slslam.bench.spec import SpecError
from slslam.cli import main

REPO = Path(__file__).resolve().parents[2]
SMOKE = REPO / "benchmarks" / "specs" / "smoke.yaml"


def _spec(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "spec.yaml"
    path.write_text(text)
    return path


MINIMAL = """
sequences:
  s: {sim: {preset: loop, frames: 30, lidar: false}}
configurations:
  c: {point_frontend: orb}
"""


@pytest.mark.parametrize(
    ("text", "where"),
    [
        (MINIMAL.replace("c: {point", "c: {kind: radar, point"), "configurations.c.kind"),
        (MINIMAL.replace("frames: 30", "frames: 30, fog: true"), "sequences.s.sim.fog"),
        (MINIMAL.replace("frames: 30", "frames: many"), "sequences.s.sim.frames"),
        (MINIMAL.replace("frames: 30", "frames: 30, seed: 3"), "sequences.s.sim.seed"),
        (MINIMAL + "seeds: [1, 1]\n", "seeds"),
        (MINIMAL + "report: [ate, speed]\n", "report[1]"),
        (MINIMAL + "colour: red\n", "colour"),
        (MINIMAL.replace("c: {point_frontend: orb}", "c: {kind: lidar}"), "configurations.c"),
        (MINIMAL.replace("point_frontend: orb", "point_frontend: sift"), "point_frontend"),
        ("configurations:\n  c: {}\n", "sequences"),
    ],
)
def test_spec_errors_name_file_and_key(tmp_path: Path, text: str, where: str) -> None:
    path = _spec(tmp_path, text)
    with pytest.raises(SpecError) as info:
        load_spec(path)
    message = str(info.value)
    assert str(path) in message and where in message, message


def test_bad_config_key_names_the_configuration(tmp_path: Path) -> None:
    path = _spec(
        tmp_path,
        MINIMAL.replace("{point_frontend: orb}", "{overlay: {tracking: {use_lynes: true}}}"),
    )
    with pytest.raises(SpecError, match=r"spec\.yaml: configurations\.c: .*use_lynes"):
        plan_cells(load_spec(path))


def test_cli_bad_spec_is_one_error_line(tmp_path: Path, capsys) -> None:
    path = _spec(tmp_path, MINIMAL.replace("frames: 30", "frames: -4"))
    assert main(["bench", str(path), "--workers", "1", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "error:" in err and "sequences.s.sim" in err and "Traceback" not in err


def test_every_shipped_spec_parses() -> None:
    """Each spec under benchmarks/specs loads (its keys, sequences and configurations checked)."""
    specs = sorted((REPO / "benchmarks" / "specs").glob("*.yaml"))
    assert {p.stem for p in specs} >= {"smoke", "recovery", "euroc", "kitti", "inertial"}
    for path in specs:
        spec = load_spec(path)
        assert spec.configurations and spec.sequences, path


def test_a_groundtruth_file_joins_the_cell_key(tmp_path: Path) -> None:
    """A recorded sequence's ``groundtruth:`` (relative to the spec) is part of its cells' keys,
    and a missing file is an error naming the sequence; cells without one keep their keys."""
    data = tmp_path / "seq"
    (data / "mav0").mkdir(parents=True)
    gt = tmp_path / "gt.tum"
    gt.write_text("0 0 0 0 0 0 0 1\n")
    base = "sequences:\n  s: {path: seq%s}\nconfigurations:\n  c: {point_frontend: orb}\n"
    plain = plan_cells(load_spec(_spec(tmp_path, base % "")))[0]
    scored = plan_cells(load_spec(_spec(tmp_path, base % ", groundtruth: gt.tum")))[0]
    assert scored.key != plain.key
    assert scored.material["sequence"]["groundtruth"]["path"] == str(gt.resolve())
    assert "groundtruth" not in plain.material["sequence"]
    gt.unlink()
    with pytest.raises(SpecError, match=r"sequences\.s\.groundtruth"):
        plan_cells(load_spec(_spec(tmp_path, base % ", groundtruth: gt.tum")))
    with pytest.raises(SpecError, match="groundtruth"):
        load_spec(
            _spec(tmp_path, MINIMAL.replace("lidar: false}", "lidar: false}, groundtruth: x"))
        )


def test_keys_change_only_with_the_configuration() -> None:
    spec = load_spec(SMOKE)
    before = {c.id: c.key for c in plan_cells(spec)}
    assert len(before) == 4 and len(set(before.values())) == 4
    orb = spec.configuration("orb")
    changed = dataclasses.replace(
        orb, overlay={"tracking": {"use_lines": False, "min_inliers": 12}}
    )
    relabelled = dataclasses.replace(spec.configuration("orb_lines"), label="renamed")
    spec2 = dataclasses.replace(spec, configurations=(relabelled, changed))
    after = {c.id: c.key for c in plan_cells(spec2)}
    assert {i for i in before if before[i] != after[i]} == {
        "loop_30/orb/seed0",
        "loop_30/orb/seed1",
    }


def test_marked_block_replaced_and_the_rest_kept(tmp_path: Path) -> None:
    text = "# T\nabove\n<!-- slslam-bench:x begin -->\nold\n<!-- slslam-bench:x end -->\nbelow\n"
    new = replace_block(text, "x", "| a |\n|---|")
    assert new == (
        "# T\nabove\n<!-- slslam-bench:x begin -->\n| a |\n|---|\n"
        "<!-- slslam-bench:x end -->\nbelow\n"
    )
    assert replace_block(new, "x", "| a |\n|---|") == new
    path = tmp_path / "R.md"
    path.write_text("no markers\n")
    with pytest.raises(ValueError, match=r"R\.md: no block 'x'"):
        update_file(path, "x", "t")


@pytest.fixture(scope="module")
def ray_session():
    """One local Ray session with 2 CPUs for the module, in its own short temporary folder."""
    if ray is None:
        pytest.skip("Ray is not installed (pip install 'slslam[cluster]')")
    temp = tempfile.mkdtemp(prefix="slr-", dir="/tmp")
    ray.init(
        address="local", num_cpus=2, include_dashboard=False, log_to_driver=False, _temp_dir=temp
    )
    yield
    ray.shutdown()
    shutil.rmtree(temp, ignore_errors=True)


@pytest.fixture(scope="module")
def sweeps(ray_session, tmp_path_factory):
    """The smoke spec run inline and on Ray (2 workers), with shared simulated inputs."""
    root = tmp_path_factory.mktemp("bench")
    spec = load_spec(SMOKE)
    inline = run_bench(spec, root / "inline", workers=1, data_dir=root / "inputs", progress=False)
    on_ray = run_bench(spec, root / "ray", workers=2, data_dir=root / "inputs", progress=False)
    return spec, root, inline, on_ray


def _deterministic(record: dict) -> tuple:
    return record["status"], record["result"], record["trajectory_sha256"], record["key"]


def test_ray_cells_equal_inline_cells(sweeps) -> None:
    _, root, inline, on_ray = sweeps
    assert on_ray.backend.startswith("ray") and inline.backend == "inline"
    assert len(on_ray.ran) == len(inline.ran) == 4 and not on_ray.failed
    for cell_id in inline.records:
        assert _deterministic(on_ray.records[cell_id]) == _deterministic(inline.records[cell_id])
        assert on_ray.records[cell_id]["result"]["ate_rmse_m"] is not None
    assert len(compare_results(root / "inline", root / "ray")["same"]) == 4
    # the Ray cells ran in worker processes, not in this one
    assert os.getpid() not in {r["measurements"]["pid"] for r in on_ray.records.values()}


def test_rerun_runs_nothing_and_a_change_reruns_its_cells(sweeps) -> None:
    spec, root, _, on_ray = sweeps
    again = run_bench(spec, root / "ray", workers=2, data_dir=root / "inputs", progress=False)
    assert again.ran == [] and len(again.cached) == 4
    assert {i: _deterministic(r) for i, r in again.records.items()} == {
        i: _deterministic(r) for i, r in on_ray.records.items()
    }
    orb = dataclasses.replace(
        spec.configuration("orb"), overlay={"tracking": {"use_lines": False, "min_inliers": 12}}
    )
    changed = dataclasses.replace(spec, configurations=(spec.configuration("orb_lines"), orb))
    rerun = run_bench(changed, root / "ray", workers=2, data_dir=root / "inputs", progress=False)
    assert sorted(rerun.ran) == ["loop_30/orb/seed0", "loop_30/orb/seed1"]
    assert sorted(rerun.cached) == ["loop_30/orb_lines/seed0", "loop_30/orb_lines/seed1"]


def test_results_pages_and_block(sweeps, tmp_path: Path) -> None:
    spec, root, inline, _ = sweeps
    info = write_results(spec, root / "inline", inline)
    summary = (root / "inline" / "summary.md").read_text()
    assert "| loop_30 | ORB + lines | 2/2 |" in summary and "±" in summary
    assert (root / "inline" / "summary.csv").read_text().count("\n") == 3
    assert (root / "inline" / "ate.png").stat().st_size > 0
    assert (root / "inline" / "trajectories_loop_30.png").stat().st_size > 0
    assert info["cells"] == 4 and not info["not_run"]
    readme = tmp_path / "README.md"
    readme.write_text("keep\n<!-- slslam-bench:smoke begin -->\n<!-- slslam-bench:smoke end -->\n")
    code = main(
        ["bench", "report", str(SMOKE), "--out", str(root / "inline"), "--update", str(readme)]
    )
    assert code == 0
    text = readme.read_text()
    assert text.startswith("keep\n") and "| loop_30 | ORB points | 2/2 |" in text


def test_failing_cell_is_reported_and_the_others_finish(sweeps, tmp_path: Path) -> None:
    _, root, _, _ = sweeps
    (tmp_path / "empty").mkdir()
    path = _spec(
        tmp_path,
        f"""
seeds: [0]
sequences:
  loop_30: {{sim: {{preset: loop, frames: 30, light: 1.0, lidar: false}}}}
  broken: {{path: {tmp_path / "empty"}}}
configurations:
  orb: {{point_frontend: orb, overlay: {{tracking: {{use_lines: false}}}}}}
""",
    )
    run = run_bench(
        load_spec(path), tmp_path / "out", workers=2, data_dir=root / "inputs", progress=False
    )
    assert run.failed == ["broken/orb/seed0"]
    bad = run.records["broken/orb/seed0"]
    assert bad["status"] == "failed" and "unknown dataset layout" in bad["error"]
    assert run.records["loop_30/orb/seed0"]["status"] == "ok"
    assert (tmp_path / "out" / "cells" / "broken" / "orb" / "seed0.json").is_file()


@pytest.mark.parametrize("workers", [1, 2])
def test_timed_out_cell_is_reported(sweeps, tmp_path: Path, workers: int) -> None:
    _, root, _, _ = sweeps
    path = _spec(
        tmp_path,
        """
seeds: [0]
timeout_s: 0.3
sequences:
  loop_30: {sim: {preset: loop, frames: 30, light: 1.0, lidar: false}}
configurations:
  orb_lines: {point_frontend: orb}
""",
    )
    run = run_bench(
        load_spec(path), tmp_path / "out", workers=workers, data_dir=root / "inputs", progress=False
    )
    record = run.records["loop_30/orb_lines/seed0"]
    assert record["status"] == "timeout" and "timeout of 0.3 s" in record["error"]
    assert run.failed == ["loop_30/orb_lines/seed0"]


@pytest.mark.parametrize(
    ("workers", "signame"),
    [
        (1, "SIGINT"),
        pytest.param(
            2,
            "SIGTERM",
            marks=pytest.mark.xfail(
                strict=False,
                reason="a SIGTERM that lands while Ray's core worker is mid-call can crash "
                "Ray's own driver (exit 1 with its C++ stack); seen in 2 of about 10 CI runs",
            ),
        ),
    ],
)
def test_interrupt_keeps_finished_cells(sweeps, tmp_path: Path, workers: int, signame: str) -> None:
    """SIGINT / SIGTERM to `slslam bench` (inline / on its own local Ray) after the first cell:
    that cell's record stays, the summary says what is missing, the exit code is 128 + the
    signal, and a rerun completes it."""
    import signal
    import subprocess
    import sys
    import time

    _, root, _, _ = sweeps
    out = tmp_path / "out"
    import slslam

    # the slslam this test imported (installed, or a source tree holding its built core)
    env = dict(os.environ, PYTHONPATH=str(Path(slslam.__file__).resolve().parents[1]))
    command = [
        sys.executable,
        "-m",
        "slslam",
        "bench",
        str(SMOKE),
        "--workers",
        str(workers),
        "--out",
        str(out),
        "--data-dir",
        str(root / "inputs"),
        "--no-plots",
    ]
    proc = subprocess.Popen(
        command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    deadline = time.monotonic() + 120
    finished: list[Path] = []
    while proc.poll() is None and time.monotonic() < deadline:
        finished = sorted((out / "cells").glob("*/*/seed*.json"))
        if finished:
            break
        time.sleep(0.05)
    signum = getattr(signal, signame)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signum, err[-2000:]
    assert "stopped" in err and "Traceback" not in err
    first = finished[0].relative_to(out / "cells").with_suffix("").as_posix()
    info = __import__("json").loads((out / "bench.json").read_text())
    assert first in info["ran"] and info["not_run"]
    again = run_bench(load_spec(SMOKE), out, workers=1, data_dir=root / "inputs", progress=False)
    assert first in again.cached and len(again.ran) == 4 - len(again.cached)


def test_lidar_cell(tmp_path: Path) -> None:
    """A LiDAR configuration runs the LiDAR pipeline on a simulated LiDAR + IMU sequence."""
    import slslam.lidar

    if not slslam.lidar.available():
        pytest.skip("slslam._core was built without PCL: no LiDAR pipeline")
    path = _spec(
        tmp_path,
        """
seeds: [0]
sequences:
  straight: {sim: {preset: straight, frames: 40, cameras: false, lidar: true}}
configurations:
  lidar_odometry: {kind: lidar, lidar: {loop_closure: false}}
""",
    )
    run = run_bench(load_spec(path), tmp_path / "out", workers=1, progress=False)
    record = run.records["straight/lidar_odometry/seed0"]
    assert record["status"] == "ok", record.get("error")
    assert record["result"]["frames"] == 20 and record["result"]["ate_rmse_m"] < 1.0
    assert record["trajectory_sha256"] is not None
