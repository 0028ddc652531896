"""KITTI stereo benchmark: slslam per configuration on KITTI odometry sequences and raw drives.

    python benchmarks/kitti.py [--sequences DIR ...] [--configs default,orb_lines,xfeat_lines]
        [--frames N] [--out DIR]

Each DIR is a KITTI odometry sequence (``sequences/NN``, scored against ``poses/NN.txt``) or a raw
drive (``..._sync``, scored against a ``reference_*.tum`` trajectory beside it when there is one:
the shared drive ships ORB-SLAM3 v1.0's stereo trajectory, an estimate run beside slslam, not
ground truth). Without ``--sequences`` the shared raw drive ``kitti_raw_2011_09_26_drive_0001``
is used. Per sequence and configuration it prints and writes (kitti.md, kitti.json): frames
posed, maps at the end, the path length against the reference's, ATE RMSE (evo APE, translation,
SE3 Umeyama alignment, no scale) in metres and in % of the reference's path, and frames/s (frames
/ the summed per-frame ``total`` times).

Published numbers: the ORB-SLAM3 paper (Campos et al., T-RO 2021) reports no KITTI stereo table,
and no paper text with KITTI numbers was available when this script was written, so no published
column is printed; the ORB-SLAM3 reference trajectory above is compared instead.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
from evo.core.trajectory import PosePath3D

from slslam.config import Config, default_config
from slslam.datasets import KittiSequence, read_trajectory
from slslam.eval.report import evaluate
from slslam.tracking import run_sequence

from common import RESULTS_DIR, SHARED_DATA, machine_line, write_results

SHARED_DRIVE = SHARED_DATA / "kitti_raw_2011_09_26_drive_0001"
#: name -> (point front end or None for the library's default, lines)
CONFIGS: dict[str, tuple[str | None, bool]] = {
    "default": (None, True),
    "orb_lines": ("orb", True),
    "orb": ("orb", False),
    "xfeat_lines": ("xfeat", True),
}
DEFAULT_CONFIGS = ("default", "orb_lines", "xfeat_lines")


def make_config(name: str) -> Config:
    frontend, lines = CONFIGS[name]
    base = default_config(frontend)
    return dataclasses.replace(base, tracking=dataclasses.replace(base.tracking, use_lines=lines))


def path_length_m(path: PosePath3D) -> float:
    """Summed distance between consecutive positions [m]."""
    return float(np.linalg.norm(np.diff(path.positions_xyz, axis=0), axis=1).sum())


def reference_for(seq: KittiSequence) -> tuple[Path | None, PosePath3D | None, str]:
    """The reference file to give the run (None: the sequence's own ground truth, or none), the
    trajectory to score against, and what it is."""
    if seq.groundtruth_path is not None:
        return None, seq.groundtruth(), f"ground truth {seq.groundtruth_path}"
    candidates = sorted(seq.root.glob("reference_*.tum"))
    if candidates:
        reference = candidates[0]
        return reference, read_trajectory(reference, "tum"), f"reference estimate {reference.name}"
    return None, None, "none"


def run_one(
    seq: KittiSequence,
    reference: tuple[Path | None, PosePath3D | None, str],
    name: str,
    out: Path,
    frames: int | None,
) -> dict:
    reference_path, gt, _ = reference
    summary = run_sequence(
        # the folder, not the opened sequence: metrics.json names the dataset by its path
        seq.root,
        out,
        make_config(name),
        max_frames=frames,
        progress=False,
        groundtruth=reference_path,
    )
    m = summary.metrics
    traj_file = out / "trajectory.tum"
    estimate = read_trajectory(traj_file, "tum") if traj_file.stat().st_size else None
    row: dict = {
        "frames": m["frames"],
        "posed": m["tracked_frames"],
        "maps": m.get("maps"),
        "frontend": m["frontend"],
        "lines": m["lines"],
        "path_m": path_length_m(estimate) if estimate is not None else None,
    }
    if gt is not None:
        n = m["frames"]
        gt_path = PosePath3D(poses_se3=gt.poses_se3[:n])
        row["reference_path_m"] = path_length_m(gt_path)
        if estimate is not None and estimate.num_poses >= 3:
            ate = evaluate(estimate, gt, align="se3", rpe_delta=None, plot=False).ape.stats["rmse"]
            row["ate_m"] = float(ate)
            row["ate_percent_of_path"] = 100.0 * float(ate) / row["reference_path_m"]
        if row["path_m"] is not None:
            row["path_error_percent"] = (
                100.0 * (row["path_m"] - row["reference_path_m"]) / row["reference_path_m"]
            )
    totals_s = sum(r.timings_ms.total for r in summary.results) / 1e3
    row["fps"] = m["frames"] / totals_s if totals_s > 0 else None
    return row


def _fmt(value, digits: int = 3) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def table(results: dict) -> str:
    lines = [
        "| sequence | config | posed | maps | path [m] | ref. path [m] | path err. [%] | "
        "ATE [m] | ATE [% path] | frames/s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for seq, per_config in results.items():
        for name, r in per_config.items():
            lines.append(
                f"| {seq} | {name} ({r['frontend']}{' + lines' if r['lines'] else ''}) | "
                f"{r['posed']}/{r['frames']} | {r['maps']} | {_fmt(r['path_m'], 2)} | "
                f"{_fmt(r.get('reference_path_m'), 2)} | {_fmt(r.get('path_error_percent'), 2)} | "
                f"{_fmt(r.get('ate_m'))} | {_fmt(r.get('ate_percent_of_path'), 2)} | "
                f"{_fmt(r['fps'], 1)} |"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sequences", nargs="+", type=Path, default=None)
    parser.add_argument("--configs", default=",".join(DEFAULT_CONFIGS))
    parser.add_argument("--frames", type=int, default=None)
    parser.add_argument("--out", type=Path, default=RESULTS_DIR / "kitti")
    args = parser.parse_args(argv)
    names = [n.strip() for n in args.configs.split(",") if n.strip()]
    unknown = [n for n in names if n not in CONFIGS]
    if unknown:
        parser.error(f"unknown configuration(s) {unknown}; choose from {sorted(CONFIGS)}")
    folders = args.sequences or [SHARED_DRIVE]
    missing = [f for f in folders if not f.is_dir()]
    if missing:
        print(f"KITTI data not found: {', '.join(map(str, missing))}", file=sys.stderr)
        return 2
    results: dict = {}
    for folder in folders:
        seq = KittiSequence(folder)
        reference = reference_for(seq)
        print(f"{folder.name}: scored against {reference[2]}")
        results[folder.name] = {
            name: run_one(seq, reference, name, args.out / folder.name / name, args.frames)
            for name in names
        }
    text = table(results)
    print(text)
    print(machine_line())
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "kitti.md").write_text(text + "\n")
    (args.out / "kitti.json").write_text(json.dumps(results, indent=2) + "\n")
    write_results("kitti", results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
