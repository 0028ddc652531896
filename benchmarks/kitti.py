"""KITTI stereo benchmark: slslam per configuration on KITTI odometry sequences and raw drives.

    python benchmarks/kitti.py [--sequences DIR ...] [--configs default,orb_lines,xfeat_lines]
        [--frames N] [--out DIR] [--published FILE]

Each DIR is a KITTI odometry sequence (``sequences/NN``, scored against ``poses/NN.txt``) or a raw
drive (``..._sync``, scored against a ``reference_*.tum`` trajectory beside it when there is one:
the shared drive ships ORB-SLAM3 v1.0's stereo trajectory, an estimate run beside slslam, not
ground truth). Without ``--sequences`` the shared raw drive ``kitti_raw_2011_09_26_drive_0001``
is used. Per sequence and configuration it prints and writes (kitti.md, kitti.json): frames
posed, maps at the end, the path length against the reference's, ATE RMSE (evo APE, translation,
SE3 Umeyama alignment, no scale) in metres and in % of the reference's path, KITTI's relative
errors t_rel [%] and r_rel [deg/100 m] (odometry sequences with every frame posed, see below),
and frames/s (frames / the summed per-frame ``total`` times).

t_rel / r_rel: the KITTI odometry devkit's metric, computed here as its evaluate_odometry.cpp
does (``kitti_relative_errors``): from every 10th frame, for each length 100, 200, ..., 800 m of
ground-truth path, the segment ends at the first frame whose ground-truth distance travelled
exceeds that length; the error is ``inv(inv(E_first) E_last) inv(G_first) G_last``, its rotation
angle and translation norm divided by the length, and the sequence's numbers are the means over
its segments (in %, and deg per 100 m). No alignment (the metric is relative). The devkit needs a
pose for every frame, so a run that leaves frames unposed gets "-"; so does a run shorter than
100 m (no segment). With ``--frames N`` the segments are those inside the first N frames.

Published numbers (``published_kitti.yaml``, ``--published``): ORB-SLAM2's stereo KITTI table
(Mur-Artal & Tardos, T-RO 2017, Table I: t_rel, r_rel and the absolute RMSE t_abs for 00-10),
printed in their own columns beside slslam's on the rows of sequences 00-10, one column per
metric (t_rel and r_rel the same metric as slslam's; t_abs beside slslam's ATE but not in its
column: the paper does not state its alignment). Sequences the file reports that were not run
are listed too, with "-" in the measured columns. No ORB-SLAM3 KITTI stereo table was found
(see the file's note); the raw drive is compared with the ORB-SLAM3 reference trajectory above.
Published rows are for full sequences: a ``--frames`` run is not comparable with them.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path

import numpy as np
from evo.core.trajectory import PosePath3D, PoseTrajectory3D

from slslam.config import Config, default_config
from slslam.datasets import KittiSequence, read_trajectory
from slslam.errors import InputError
from slslam.eval.metrics import associate
from slslam.eval.report import evaluate
from slslam.tracking import run_sequence

from common import RESULTS_DIR, SHARED_DATA, load_published_sources, machine_line, write_results

HERE = Path(__file__).resolve().parent
PUBLISHED = HERE / "published_kitti.yaml"
SHARED_DRIVE = SHARED_DATA / "kitti_raw_2011_09_26_drive_0001"
#: KITTI odometry's training sequences, those with public ground truth.
SEQUENCES = tuple(f"{i:02d}" for i in range(11))
#: Published metrics: key in published_kitti.yaml -> (column title, decimals as printed).
PUBLISHED_METRICS = {
    "t_rel": ("t_rel [%]", 2),
    "r_rel": ("r_rel [deg/100 m]", 2),
    "t_abs": ("t_abs [m]", 1),
}
#: The KITTI devkit's segment lengths [m] and the frames between segment starts.
KITTI_LENGTHS_M = (100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0)
KITTI_STEP_FRAMES = 10
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


def sequence_key(name: str) -> str | None:
    """``00`` ... ``10`` for an odometry sequence folder of that name, else None."""
    return name if name in SEQUENCES else None


def load_published(path: Path) -> dict:
    """The published columns: ``{source: {label, citation, values {seq: {metric: value}}}}``;
    a bad file raises InputError naming the file and the key (common.load_published_sources)."""
    return load_published_sources(path, _check_kitti_values)


def _check_kitti_values(where: str, values) -> None:
    if not isinstance(values, dict):
        raise InputError(None, f"{where}: expected a mapping sequence -> {{metric: value}}")
    for seq, metrics in values.items():
        if seq not in SEQUENCES:
            raise InputError(
                None, f"{where}.{seq}: unknown sequence (quoted names {', '.join(SEQUENCES)})"
            )
        if not isinstance(metrics, dict) or not metrics:
            raise InputError(None, f"{where}.{seq}: expected a mapping metric -> value")
        for metric, value in metrics.items():
            if metric not in PUBLISHED_METRICS:
                raise InputError(
                    None, f"{where}.{seq}.{metric}: unknown metric ({', '.join(PUBLISHED_METRICS)})"
                )
            if (
                isinstance(value, bool)
                or not isinstance(value, int | float)
                or not math.isfinite(value)
                or not 0 <= value < 1000
            ):
                raise InputError(None, f"{where}.{seq}.{metric}: {value!r} is not a number >= 0")


def kitti_relative_errors(gt_poses: np.ndarray, est_poses: np.ndarray) -> dict:
    """KITTI odometry devkit's t_rel [%] and r_rel [deg/100 m] of one sequence (its
    ``calcSequenceErrors`` and mean): ``gt_poses`` and ``est_poses`` are (N, 4, 4) poses of the
    same frames (T_world_cam0, any world for each). Returns ``t_rel_percent``,
    ``r_rel_deg_per_100m`` (None without a segment) and ``segments``. In double precision where
    the devkit sums distances in float: a segment end can differ by a frame at a tie."""
    gt = np.asarray(gt_poses, dtype=float)
    est = np.asarray(est_poses, dtype=float)
    if gt.shape != est.shape or gt.ndim != 3 or gt.shape[1:] != (4, 4):
        raise InputError(None, f"need two (N, 4, 4) pose arrays, got {gt.shape} and {est.shape}")
    steps = np.linalg.norm(np.diff(gt[:, :3, 3], axis=0), axis=1)
    dist = np.concatenate([[0.0], np.cumsum(steps)])
    t_errors: list[float] = []
    r_errors: list[float] = []
    for first in range(0, len(gt), KITTI_STEP_FRAMES):
        for length in KITTI_LENGTHS_M:
            # the first frame whose distance exceeds dist[first] + length (dist is non-decreasing)
            last = int(np.searchsorted(dist, dist[first] + length, side="right"))
            if last >= len(gt):
                continue
            delta_gt = np.linalg.inv(gt[first]) @ gt[last]
            delta_est = np.linalg.inv(est[first]) @ est[last]
            error = np.linalg.inv(delta_est) @ delta_gt
            cos_angle = 0.5 * (np.trace(error[:3, :3]) - 1.0)
            r_errors.append(math.acos(max(min(cos_angle, 1.0), -1.0)) / length)
            t_errors.append(float(np.linalg.norm(error[:3, 3])) / length)
    if not t_errors:
        return {"t_rel_percent": None, "r_rel_deg_per_100m": None, "segments": 0}
    return {
        "t_rel_percent": 100.0 * float(np.mean(t_errors)),
        "r_rel_deg_per_100m": 100.0 * math.degrees(float(np.mean(r_errors))),
        "segments": len(t_errors),
    }


def relative_errors_of_run(estimate, gt, frames: int) -> dict:
    """``kitti_relative_errors`` of a run's estimate against the ground truth's first ``frames``
    poses, matched by timestamp; all None when a frame has no estimated pose (the devkit needs
    every one)."""
    none = {"t_rel_percent": None, "r_rel_deg_per_100m": None, "segments": None}
    if estimate is None or estimate.num_poses < frames:
        return none
    gt_run = PoseTrajectory3D(
        poses_se3=gt.poses_se3[:frames], timestamps=np.asarray(gt.timestamps)[:frames]
    )
    try:
        ref, est = associate(gt_run, estimate)
    except InputError:
        return none
    if ref.num_poses != frames:
        return none
    return kitti_relative_errors(np.array(ref.poses_se3), np.array(est.poses_se3))


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
        if reference_path is None and isinstance(gt, PoseTrajectory3D):  # poses/NN.txt
            row.update(relative_errors_of_run(estimate, gt, n))
    totals_s = sum(r.timings_ms.total for r in summary.results) / 1e3
    row["fps"] = m["frames"] / totals_s if totals_s > 0 else None
    return row


def _fmt(value, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return f"{value:.{digits}f}"


def published_columns(published: dict) -> list[tuple[str, str]]:
    """(source, metric) of each published column: the metrics a source reports, in
    PUBLISHED_METRICS order."""
    return [
        (source, metric)
        for source, entry in published.items()
        for metric in PUBLISHED_METRICS
        if any(metric in v for v in entry["values"].values())
    ]


def table(results: dict, published: dict | None = None) -> str:
    """One row per sequence and configuration run (``results``: ``{sequence: {config: row}}``),
    slslam's columns first, then one column per published source and metric, filled on the rows
    of sequences 00-10; rows for the published sequences not run follow, "-" where measured."""
    published = published or {}
    columns = published_columns(published)
    head = [
        "sequence", "config", "posed", "maps", "path [m]", "ref. path [m]", "path err. [%]",
        "ATE [m]", "ATE [% path]", "t_rel [%]", "r_rel [deg/100 m]", "frames/s",
    ] + [f"{published[s]['label']} {PUBLISHED_METRICS[m][0]}" for s, m in columns]  # fmt: skip
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]

    def published_cells(key: str | None) -> list[str]:
        return [
            _fmt(published[s]["values"].get(key, {}).get(m), PUBLISHED_METRICS[m][1])
            for s, m in columns
        ]

    for seq, per_config in results.items():
        cells = published_cells(sequence_key(seq))
        for name, r in per_config.items():
            measured = [
                seq,
                f"{name} ({r['frontend']}{' + lines' if r['lines'] else ''})",
                f"{r['posed']}/{r['frames']}",
                str(r["maps"]),
                _fmt(r["path_m"], 2),
                _fmt(r.get("reference_path_m"), 2),
                _fmt(r.get("path_error_percent"), 2),
                _fmt(r.get("ate_m")),
                _fmt(r.get("ate_percent_of_path"), 2),
                _fmt(r.get("t_rel_percent"), 2),
                _fmt(r.get("r_rel_deg_per_100m"), 2),
                _fmt(r["fps"], 1),
            ]
            lines.append("| " + " | ".join(measured + cells) + " |")
    run = {sequence_key(seq) for seq in results}
    for key in SEQUENCES:  # the published sequences not run, for their columns
        if key not in run and any(key in p["values"] for p in published.values()):
            lines.append("| " + " | ".join([key] + ["-"] * 11 + published_cells(key)) + " |")
    return "\n".join(lines)


def table_notes(published: dict, frames: int | None) -> list[str]:
    """What the table's columns are, and where each published column is from."""
    notes = [
        "ATE: evo APE translation RMSE [m] after an SE3 Umeyama alignment, against the "
        "reference named per sequence. t_rel [%] / r_rel [deg/100 m]: the KITTI devkit's "
        "relative errors over 100-800 m segments against poses/NN.txt ('-': a frame unposed, "
        "no ground truth, or under 100 m). frames/s: frames / summed per-frame tracking time.",
        *(
            f"{p['label']} (t_rel, r_rel: KITTI devkit; t_abs: absolute translation RMSE, "
            f"alignment not stated, not slslam's ATE column): {' '.join(p['citation'].split())}"
            + (f" {' '.join(p['note'].split())}" if p.get("note") else "")
            for p in published.values()
        ),
    ]
    if frames:
        notes.append(
            f"First {frames} frames of each sequence only: the published numbers are for full "
            "sequences and are not comparable with these."
        )
    return notes


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sequences", nargs="+", type=Path, default=None)
    parser.add_argument("--configs", default=",".join(DEFAULT_CONFIGS))
    parser.add_argument("--frames", type=int, default=None)
    parser.add_argument("--out", type=Path, default=RESULTS_DIR / "kitti")
    parser.add_argument(
        "--published", type=Path, default=PUBLISHED, help="published numbers (YAML)"
    )
    args = parser.parse_args(argv)
    names = [n.strip() for n in args.configs.split(",") if n.strip()]
    unknown = [n for n in names if n not in CONFIGS]
    if unknown:
        parser.error(f"unknown configuration(s) {unknown}; choose from {sorted(CONFIGS)}")
    try:
        published = load_published(args.published)
    except InputError as exc:
        parser.error(str(exc))
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
    text = table(results, published)
    notes = table_notes(published, args.frames)
    print(text)
    for note in notes:
        print(f"- {note}")
    print(machine_line())
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "kitti.md").write_text(text + "\n\n" + "\n".join(f"- {n}" for n in notes) + "\n")
    # Sequences at the top level as before (frontend_table.py reads them), the published
    # numbers and the notes beside them.
    document = {**results, "published": published, "notes": notes}
    (args.out / "kitti.json").write_text(json.dumps(document, indent=2) + "\n")
    write_results("kitti", document)
    return 0


if __name__ == "__main__":
    sys.exit(main())
