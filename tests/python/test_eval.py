import copy
import json

import numpy as np
import pytest
from evo.core import metrics, sync
from evo.core.trajectory import PoseTrajectory3D
from evo.tools import file_interface
from scipy.spatial.transform import Rotation

from slslam.cli import main
from slslam.datasets import read_trajectory, write_trajectory
from slslam.errors import InputError
from slslam.eval import compute_ape, compute_rpe, evaluate

from conftest import shared_path

NOISE_M = 0.01


def _perturbed_copy(gt: PoseTrajectory3D, seed: int = 3, scale: float = 1.0) -> PoseTrajectory3D:
    """gt in another world frame (known rigid transform), times scale, plus position noise."""
    rng = np.random.default_rng(seed)
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("zyx", [30, -10, 5], degrees=True).as_matrix()
    T[:3, 3] = [2.0, -1.0, 0.5]
    est = copy.deepcopy(gt)
    est.scale(scale)
    est.transform(T)
    est = PoseTrajectory3D(
        est.positions_xyz + rng.normal(0, NOISE_M, est.positions_xyz.shape),
        est.orientations_quat_wxyz,
        est.timestamps,
    )
    return est


def _evo_reference_rmse(est_path, gt_path, correct_scale=False) -> float:
    """APE RMSE computed with evo's API alone, as an evo user would."""
    ref = file_interface.read_euroc_csv_trajectory(gt_path)
    est = file_interface.read_tum_trajectory_file(est_path)
    ref, est = sync.associate_trajectories(ref, est, max_diff=0.01)
    est.align(ref, correct_scale=correct_scale)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    return ape.get_statistic(metrics.StatisticsType.rmse)


def test_cli_eval_matches_evo_api_on_real_euroc_groundtruth(tmp_path):
    gt_path = shared_path("euroc_groundtruth_leftcam", "V101_GT.txt")
    gt = read_trajectory(gt_path)
    est_path = write_trajectory(tmp_path / "est.tum", _perturbed_copy(gt))
    out = tmp_path / "out"
    assert main(["eval", str(est_path), str(gt_path), "--out", str(out)]) == 0
    report = json.loads((out / "metrics.json").read_text())
    expected = _evo_reference_rmse(est_path, gt_path)
    assert report["ape"]["rmse"] == pytest.approx(expected, abs=1e-6)
    # The rigid transform is undone by the alignment: what is left is the noise, sqrt(3) sigma.
    assert report["ape"]["rmse"] == pytest.approx(np.sqrt(3) * NOISE_M, rel=0.05)
    assert report["ape"]["options"]["num_poses"] == gt.num_poses
    assert (out / "ape.png").stat().st_size > 10_000


def test_alignment_modes(tmp_path):
    gt = read_trajectory(shared_path("euroc_groundtruth_leftcam", "V101_GT.txt"))
    scaled = _perturbed_copy(gt, scale=1.2)
    se3 = compute_ape(gt, scaled, align="se3").stats["rmse"]
    sim3 = compute_ape(gt, scaled, align="sim3").stats["rmse"]
    none = compute_ape(gt, scaled, align="none").stats["rmse"]
    # Sim3 undoes the 1.2 scale, which also shrinks the noise added after scaling.
    assert sim3 == pytest.approx(np.sqrt(3) * NOISE_M / 1.2, rel=0.05)
    assert se3 > 5 * sim3  # a wrong scale cannot be aligned away rigidly
    assert none > 1.0  # the world frames differ by metres
    with pytest.raises(InputError, match="unknown alignment"):
        compute_ape(gt, scaled, align="affine")  # type: ignore[arg-type]


def test_rpe_ignores_the_world_frame_and_sees_noise():
    gt = read_trajectory(shared_path("euroc_groundtruth_leftcam", "V101_GT.txt"))
    moved = copy.deepcopy(gt)
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("z", 70, degrees=True).as_matrix()
    T[:3, 3] = [10.0, -4.0, 1.0]
    moved.transform(T)
    assert compute_rpe(gt, moved, delta=1.0, align="none").stats["rmse"] < 1e-9
    assert compute_ape(gt, moved, align="none").stats["rmse"] > 1.0
    noisy = _perturbed_copy(gt)
    rpe = compute_rpe(gt, noisy, delta=10, delta_unit="frames").stats["rmse"]
    assert rpe == pytest.approx(np.sqrt(6) * NOISE_M, rel=0.1)  # difference of two noisy points


def test_trajectories_without_common_times_are_rejected():
    gt = read_trajectory(shared_path("euroc_groundtruth_leftcam", "V101_GT.txt"))
    with pytest.raises(InputError, match="cannot be associated in time"):
        shifted = PoseTrajectory3D(
            gt.positions_xyz, gt.orientations_quat_wxyz, gt.timestamps + 1000.0
        )
        evaluate(shifted, gt)


def test_cli_reports_bad_input_without_traceback(tmp_path, capsys):
    empty = tmp_path / "empty.txt"
    empty.write_text("")
    code = main(["eval", str(empty), str(empty)])
    assert code == 2
    err = capsys.readouterr().err
    assert "error:" in err and "empty" in err and "Traceback" not in err
