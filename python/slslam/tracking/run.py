"""``slslam run``: the tracker over a whole sequence, with every result written as a file.

Outputs in ``out_dir``:
    trajectory.tum   every input frame (TUM: t x y z qx qy qz qw, left camera in the map frame),
                     written and flushed frame by frame, so a run that fails midway keeps them
    frames.csv       per frame: state, counts and stage times [ms], also written as it goes
    map.ply          map points (vertices) and map lines (edges between endpoint vertices)
    metrics.json     frames, tracked ratio, median stage times, and ATE/RPE (evo, SE3 alignment,
                     over tracked frames) when the dataset has ground truth
    ape.png          the APE plot (with ground truth)
    config.yaml      the configuration used
"""

from __future__ import annotations

import csv
import logging
import statistics
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from evo.core.trajectory import PoseTrajectory3D
from scipy.spatial.transform import Rotation
from tqdm import tqdm

from slslam.config import Config, dump_config
from slslam.datasets.euroc import EurocSequence, is_euroc
from slslam.errors import DatasetError, InputError
from slslam.eval.report import evaluate, load_groundtruth, write_json
from slslam.tracking.tracker import TRACKED_STATES, Tracker, TrackResult

log = logging.getLogger(__name__)

STAGES = (
    "inference",
    "line_extraction",
    "stereo_matching",
    "matching",
    "optimisation",
    "mapping",
    "total",
)
COUNTS = (
    "keypoints",
    "lines",
    "matched_points",
    "inlier_points",
    "matched_lines",
    "inlier_lines",
    "keyframe",
    "map",
)


@dataclass
class RunSummary:
    """What a run produced: the metrics dictionary (also in metrics.json) and the output folder."""

    out_dir: Path
    metrics: dict
    results: list[TrackResult]


def open_dataset(path: str | Path) -> EurocSequence:
    """The sequence at ``path``, recognised by its layout (EuRoC ASL: a folder holding mav0/)."""
    path = Path(path)
    if not path.exists():
        raise DatasetError(path, "dataset folder not found")
    if is_euroc(path):
        return EurocSequence(path)
    raise DatasetError(
        path,
        "unknown dataset layout: slslam run reads EuRoC ASL folders (the folder holding mav0/, "
        "or mav0 itself); `slslam sim --out DIR` makes one",
    )


def _tum_line(result: TrackResult) -> str:
    q = Rotation.from_matrix(result.T_wc[:3, :3]).as_quat()  # x y z w
    t = result.T_wc[:3, 3]
    return (
        f"{result.timestamp:.9f} {t[0]:.9f} {t[1]:.9f} {t[2]:.9f} "
        f"{q[0]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f}\n"
    )


def write_ply(path: Path, points: np.ndarray, lines: np.ndarray) -> Path:
    """ASCII PLY: map points and line endpoints as vertices (points red-free grey, lines
    coloured), each line an edge between its two endpoint vertices. Written atomically."""
    n_points, n_lines = len(points), len(lines)
    vertices = np.vstack([points.reshape(-1, 3), lines.reshape(-1, 3)]) if n_lines else points
    colours = np.vstack(
        [
            np.tile([200, 200, 200], (n_points, 1)),
            np.tile([255, 140, 0], (2 * n_lines, 1)),
        ]
    ).astype(int)
    tmp = path.with_name(path.name + ".partial")
    with tmp.open("w", encoding="ascii") as f:
        f.write("ply\nformat ascii 1.0\ncomment slslam map: points, then line endpoints\n")
        f.write(f"element vertex {len(vertices)}\n")
        f.write("property float x\nproperty float y\nproperty float z\n")
        f.write("property uchar red\nproperty uchar green\nproperty uchar blue\n")
        f.write(f"element edge {n_lines}\nproperty int vertex1\nproperty int vertex2\n")
        f.write("end_header\n")
        rows = np.hstack([vertices, colours])
        np.savetxt(f, rows, fmt=["%.5f", "%.5f", "%.5f", "%d", "%d", "%d"])
        first = n_points + 2 * np.arange(n_lines)
        np.savetxt(f, np.column_stack([first, first + 1]), fmt="%d")
    tmp.replace(path)
    return path


def tracked_trajectory(results: list[TrackResult]) -> PoseTrajectory3D | None:
    """The tracked frames (OK / NEW_MAP) as an evo trajectory; None when fewer than 2."""
    tracked = [r for r in results if r.state in TRACKED_STATES]
    if len(tracked) < 2:
        return None
    return PoseTrajectory3D(
        poses_se3=[r.T_wc for r in tracked], timestamps=np.array([r.timestamp for r in tracked])
    )


def _score(estimate: PoseTrajectory3D, gt, out: Path) -> dict:
    """APE (and RPE over 1 m) against ground truth, writing ape.png. A failed evaluation (no
    timestamps in common, a trajectory shorter than the RPE delta) is logged and reported in the
    metrics; it does not fail the run, whose trajectory is already written."""
    try:
        evaluation = evaluate(estimate, gt, out_dir=out, align="se3", rpe_delta=1.0)
    except InputError as exc:
        log.warning("%s; scoring APE only", exc)
        try:
            evaluation = evaluate(estimate, gt, out_dir=out, align="se3", rpe_delta=None)
        except InputError as exc2:
            log.warning("no ATE: %s", exc2)
            return {"evaluation_error": str(exc2)}
    summary = evaluation.summary()
    return {k: summary[k] for k in ("ape", "rpe") if k in summary}


def run_sequence(
    dataset: str | Path,
    out_dir: str | Path,
    config: Config | None = None,
    max_frames: int | None = None,
    progress: bool = True,
    frontend=None,
    groundtruth: str | Path | None = None,
) -> RunSummary:
    """Runs the tracker over a sequence and writes the outputs listed in the module docstring.

    Args:
        dataset: the sequence folder (see :func:`open_dataset`).
        out_dir: output folder, created when missing.
        config: configuration; defaults when None.
        max_frames: track only the first N frames.
        progress: show a tqdm progress bar.
        frontend: a point front end to use instead of the configured one.
        groundtruth: a ground-truth trajectory file (TUM, EuRoC csv or KITTI, left camera frame)
            used instead of the sequence's own, e.g. for an excerpt that ships none.
    """
    config = config or Config()
    sequence = open_dataset(dataset)
    if groundtruth is not None and not Path(groundtruth).is_file():
        raise DatasetError(groundtruth, "ground-truth file not found")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    dump_config(config, out / "config.yaml")
    n = len(sequence) if max_frames is None else min(max_frames, len(sequence))
    results: list[TrackResult] = []
    error: BaseException | None = None
    with Tracker(sequence.camera, config, frontend=frontend) as tracker:
        log.info(
            "tracking %d frames of %s with %s points%s",
            n,
            dataset,
            tracker.frontend_name,
            " + lines" if config.tracking.use_lines else "",
        )
        with (
            (out / "trajectory.tum").open("w", encoding="ascii") as traj_file,
            (out / "frames.csv").open("w", newline="", encoding="ascii") as frames_file,
        ):
            writer = csv.writer(frames_file)
            writer.writerow(["index", "timestamp", "state", *COUNTS, *(f"{s}_ms" for s in STAGES)])
            bar = tqdm(range(n), desc="tracking", unit="frame", disable=not progress)
            try:
                for i in bar:
                    frame = sequence[i]
                    result = tracker.track(frame.left, frame.right, frame.t_ns * 1e-9)
                    results.append(result)
                    traj_file.write(_tum_line(result))
                    traj_file.flush()
                    writer.writerow(
                        [
                            result.index,
                            f"{result.timestamp:.9f}",
                            result.state,
                            *(result.counts[c] for c in COUNTS),
                            *(f"{result.timings_ms[s]:.3f}" for s in STAGES),
                        ]
                    )
                    frames_file.flush()
                    bar.set_postfix(state=result.state, pts=result.counts["inlier_points"])
            except (Exception, KeyboardInterrupt) as exc:  # keep what was tracked
                error = exc
                log.error(
                    "run stopped at frame %d: %s; writing the map and metrics so far",
                    len(results),
                    exc,
                )
        map_data = tracker.map()
    write_ply(out / "map.ply", map_data.points, map_data.lines)

    tracked = sum(r.state in TRACKED_STATES for r in results)
    metrics: dict = {
        "dataset": str(dataset),
        "frontend": tracker.frontend_name,
        "lines": config.tracking.use_lines,
        "frames": len(results),
        "tracked_frames": tracked,
        "tracked_ratio": tracked / len(results) if results else 0.0,
        "states": {
            s: sum(r.state == s for r in results) for s in sorted({r.state for r in results})
        },
        "keyframes": map_data.keyframes,
        "maps": map_data.maps,
        "map_points": len(map_data.points),
        "map_lines": len(map_data.lines),
        "local_mapping": map_data.stats,
        "median_ms": {
            s: statistics.median(r.timings_ms[s] for r in results) if results else None
            for s in STAGES
        },
    }
    estimate = tracked_trajectory(results)
    gt = None
    if groundtruth is not None:
        # Rectification only rotates the camera: positions in the cam0 and rectified frames agree,
        # so a cam0 ground truth serves the position error (APE translation part) unchanged.
        gt = load_groundtruth(groundtruth)
    elif sequence.groundtruth_path is not None:
        gt = sequence.groundtruth(frame="rectified")
    if estimate is not None and gt is not None:
        metrics.update(_score(estimate, gt, out))
    if error is not None:
        metrics["error"] = f"{type(error).__name__}: {error}"
        metrics["stopped_at_frame"] = len(results)
    write_json(out / "metrics.json", metrics)
    if error is not None:
        raise error
    return RunSummary(out, metrics, results)
