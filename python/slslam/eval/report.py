"""Evaluate an estimate file against ground truth and write ``metrics.json`` and ``ape.png``.

Ground truth may be a trajectory file (TUM, KITTI, EuRoC csv) or a EuRoC ASL folder; for a folder
the body ground truth is converted to the left camera (``T_world_cam0 = T_world_body @ T_BS``) so
that an estimate of camera poses is scored in the right frame. ``gt_body_to_cam`` does the same
for a bare EuRoC ground-truth csv, given cam0's ``sensor.yaml``.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

from evo.core.trajectory import PosePath3D

from slslam._version import __version__
from slslam.datasets.calibration import CameraCalibration
from slslam.datasets.euroc import EurocSequence, find_mav0, is_euroc
from slslam.datasets.trajectory_io import TrajectoryFormat, read_trajectory
from slslam.eval.metrics import Alignment, DeltaUnit, ErrorResult, compute_ape, compute_rpe
from slslam.eval.plots import plot_ape


@dataclass
class Evaluation:
    """Results of :func:`evaluate` and the files it wrote (None when not written)."""

    ape: ErrorResult
    rpe: ErrorResult | None
    metrics_path: Path | None
    plot_path: Path | None

    def summary(self) -> dict:
        """JSON-ready dictionary of every statistic and option."""
        out = {
            "slslam_version": __version__,
            "ape": {"unit": "m", **self.ape.stats, "options": self.ape.options},
        }
        if self.rpe is not None:
            out["rpe"] = {"unit": "m", **self.rpe.stats, "options": self.rpe.options}
        return out


def load_groundtruth(
    path: str | Path, fmt: TrajectoryFormat = "auto", gt_body_to_cam: str | Path | None = None
) -> PosePath3D:
    """Ground truth from a file or a EuRoC folder, in the left camera frame where known."""
    path = Path(path)
    if path.is_dir() and is_euroc(path):
        mav0 = find_mav0(path)
        # Only calibration and ground truth are needed; the sequence object does the framing.
        return EurocSequence(mav0).groundtruth(frame="cam0")
    traj = read_trajectory(path, fmt)
    if gt_body_to_cam is not None:
        traj.transform(CameraCalibration.from_yaml(gt_body_to_cam).T_body_cam, right_mul=True)
    return traj


def write_json(path: Path, data: dict) -> Path:
    """Write JSON atomically (temporary file + rename); NaN becomes null."""

    def clean(value):
        if isinstance(value, float) and not math.isfinite(value):
            return None
        if isinstance(value, dict):
            return {k: clean(v) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [clean(v) for v in value]
        return value

    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".partial")
    try:
        tmp.write_text(json.dumps(clean(data), indent=2) + "\n", encoding="utf-8")
        os.replace(tmp, path)
    finally:  # an interrupted write leaves neither a partial file nor a truncated final one
        tmp.unlink(missing_ok=True)
    return path


def evaluate(
    estimate: str | Path | PosePath3D,
    groundtruth: str | Path | PosePath3D,
    out_dir: str | Path | None = None,
    align: Alignment = "se3",
    max_diff_s: float = 0.01,
    rpe_delta: float | None = 1.0,
    rpe_unit: DeltaUnit = "m",
    est_format: TrajectoryFormat = "auto",
    gt_format: TrajectoryFormat = "auto",
    gt_body_to_cam: str | Path | None = None,
    plot: bool = True,
) -> Evaluation:
    """Compute APE (and RPE unless ``rpe_delta`` is None); write files into ``out_dir`` if given."""
    est = estimate if isinstance(estimate, PosePath3D) else read_trajectory(estimate, est_format)
    gt = (
        groundtruth
        if isinstance(groundtruth, PosePath3D)
        else load_groundtruth(groundtruth, gt_format, gt_body_to_cam)
    )
    ape = compute_ape(gt, est, align=align, max_diff_s=max_diff_s)
    rpe = (
        None
        if rpe_delta is None
        else compute_rpe(
            gt, est, delta=rpe_delta, delta_unit=rpe_unit, align=align, max_diff_s=max_diff_s
        )
    )
    result = Evaluation(ape=ape, rpe=rpe, metrics_path=None, plot_path=None)
    if out_dir is not None:
        out_dir = Path(out_dir)
        result.metrics_path = write_json(out_dir / "metrics.json", result.summary())
        if plot:
            result.plot_path = plot_ape(ape, out_dir / "ape.png")
    return result
