"""benchmarks/euroc.py: sequence names, the published numbers file, the left-camera ground truth,
and the table on the real EuRoC excerpt with a stand-in for a user's ORB-SLAM3 binary."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from slslam.datasets import CameraCalibration, read_trajectory
from slslam.errors import InputError

from conftest import REPO, load_benchmark, shared_path

BENCHMARKS = REPO / "benchmarks"


@pytest.fixture(scope="module")
def euroc_bench():
    yield from load_benchmark("euroc.py")


def test_sequence_names(euroc_bench):
    key = euroc_bench.sequence_key
    assert key("MH_01_easy") == "MH_01"
    assert key("V2_03_difficult") == "V2_03"
    assert key("euroc_v101_micro") == "V1_01"
    assert key("V102") == "V1_02"
    assert key("MH_06") is None
    assert key("loop_dark") is None


def test_published_file_holds_the_sl_slam_table(euroc_bench):
    published = euroc_bench.load_published(euroc_bench.PUBLISHED)
    sl = published["slslam_paper_slslam"]["values"]
    orb = published["slslam_paper_orbslam3"]["values"]
    assert sl == {"MH_01": 0.103, "MH_03": 0.072, "MH_05": 0.097, "V2_01": 0.058,
                  "V2_02": 0.059, "V2_03": 0.102}  # fmt: skip
    assert orb["MH_01"] == 0.172 and orb["V2_03"] == 0.106
    # ORB-SLAM3's own paper (stereo row of its Table II): all eleven sequences.
    own = published["orbslam3_paper"]["values"]
    assert len(own) == 11 and own["MH_01"] == 0.029 and own["V2_03"] == 0.521
    for entry in published.values():
        assert entry["citation"].strip()
    # The paper's averages are the means of its rows (to the printed 3 decimals).
    for source in ("slslam_paper_slslam", "slslam_paper_orbslam3", "orbslam3_paper"):
        values = list(published[source]["values"].values())
        assert abs(np.mean(values) - published[source]["average"]) < 0.0015


@pytest.mark.parametrize(
    ("text", "key"),
    [
        ("sources: {}\n", "sources"),
        ("sources:\n  a: {label: A, values: {}}\n", "sources.a: needs a 'citation'"),
        (
            "sources:\n  a: {label: A, citation: x, values: {MH_09: 0.1}}\n",
            "sources.a.values.MH_09",
        ),
        ("sources:\n  a: {label: A, citation: x, values: {MH_01: fast}}\n", "values.MH_01"),
        ("sources: [\n", "cannot read"),
    ],
)
def test_bad_published_file_names_file_and_key(euroc_bench, tmp_path, text, key):
    path = tmp_path / "published.yaml"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        euroc_bench.load_published(path)
    assert str(path) in str(info.value) and key in str(info.value)


def test_leftcam_groundtruth_is_cam0_in_world(euroc_bench):
    """The ORB-SLAM3 left-camera file, read by the benchmark, equals the body ground truth
    composed with cam0's T_BS (V1_02), positions and orientations."""
    leftcam = euroc_bench.leftcam_groundtruth(
        shared_path("euroc_groundtruth_leftcam", "V102_GT.txt")
    )
    body = read_trajectory(shared_path("trajectories", "V102_groundtruth.csv"), "euroc")
    T_body_cam0 = CameraCalibration.from_yaml(
        shared_path("euroc_calib", "euroc_cam0_sensor.yaml")
    ).T_body_cam
    index = {round(t, 4): i for i, t in enumerate(body.timestamps)}
    checked = 0
    for t, T_world_cam in zip(leftcam.timestamps[::50], leftcam.poses_se3[::50], strict=True):
        i = index.get(round(t, 4))
        if i is None:
            continue
        expected = body.poses_se3[i] @ T_body_cam0
        assert np.allclose(T_world_cam[:3, 3], expected[:3, 3], atol=1e-3)
        assert np.allclose(T_world_cam[:3, :3], expected[:3, :3], atol=1e-3)
        checked += 1
    assert checked >= 10


STAND_IN = """#!{python}
# Stand-in for ORB-SLAM3's stereo_euroc: writes f_<name>.txt in its format (t [ns], x y z qx qy qz
# qw) from the ground truth (T_world_cam0) offset by a fixed rigid transform, for the times asked.
import sys
import numpy as np
from scipy.spatial.transform import Rotation
vocab, settings, seq, times, name = sys.argv[1:6]
assert open(vocab).read() and open(settings).read()
gt = np.loadtxt({gt!r}, delimiter=",", comments="#")
stamps = np.loadtxt(times, dtype=np.int64, ndmin=1)
rows = []
R = Rotation.from_euler("z", 30, degrees=True)
for t in stamps:
    i = np.flatnonzero(np.abs(gt[:, 0] - t) < 1e6)
    if len(i):
        p = R.apply(gt[i[0], 1:4]) + [1.0, 2.0, 3.0]
        rows.append([t, *p, 0, 0, 0, 1])
np.savetxt("f_" + name + ".txt", np.array(rows), fmt="%.6f")
"""


def test_table_on_the_excerpt_with_orbslam3_stand_in(tmp_path):
    root = shared_path()
    gt_file = shared_path("euroc_groundtruth_leftcam", "V101_GT.txt")
    tree = tmp_path / "ORB_SLAM3"
    binary = tree / "Examples" / "Stereo" / "stereo_euroc"
    binary.parent.mkdir(parents=True)
    binary.write_text(STAND_IN.format(python=sys.executable, gt=str(gt_file)))
    binary.chmod(0o755)
    (binary.parent / "EuRoC.yaml").write_text("%YAML:1.0\n")
    (tree / "Vocabulary").mkdir()
    (tree / "Vocabulary" / "ORBvoc.txt").write_text("vocabulary\n")
    out = tmp_path / "out"
    command = [sys.executable, str(BENCHMARKS / "euroc.py"), "--root", str(root), "--frames",
               "40", "--configs", "orb", "--out", str(out), "--json", str(tmp_path / "r.json"),
               "--orbslam3", str(binary)]  # fmt: skip
    done = subprocess.run(command, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": ""})  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    rows = {line.split("|")[1].strip(): [c.strip() for c in line.split("|")[2:-1]]
            for line in done.stdout.splitlines() if line.startswith("| ")}  # fmt: skip
    header = rows["sequence"]
    excerpt = rows["V1_01 (euroc_v101_micro)"]
    assert excerpt[header.index("frames")] == "40"
    # The published columns come from the data file; the papers' sequences not found are listed.
    assert rows["MH_01"][header.index("SL-SLAM (its paper)")] == "0.103"
    assert rows["V2_03"][header.index("ORB-SLAM3 (SL-SLAM re-run)")] == "0.106"
    # The camera is static in the excerpt: ORB points hold it to a few millimetres.
    ate = float(excerpt[header.index("ORB points ATE")])
    assert 0 <= ate < 0.02
    assert float(excerpt[header.index("ORB points tracked")]) > 0.5
    # The stand-in's estimate is the ground truth moved rigidly: SE3 alignment removes it all.
    assert float(excerpt[header.index("ORB-SLAM3 (this machine) ATE")]) < 1e-4
    assert (out / "V1_01_euroc_v101_micro" / "orb" / "trajectory.tum").is_file()
    assert (out / "euroc.md").read_text().startswith("| sequence |")
