"""``slslam run``: the tracker over a whole sequence, with every result written as a file.

Outputs in ``out_dir``:
    trajectory.tum   every frame with an estimated pose (states OK, RELOCALISED, NEW_MAP; TUM:
                     t x y z qx qy qz qw, left camera in the map frame), written and flushed
                     frame by frame, so a run that fails midway keeps them; after the frame
                     loop replaced (atomically) by the same frames in the final map: each frame
                     follows its reference keyframe through loop correction, map merges and
                     global bundle adjustment (ORB-SLAM's trajectory output)
    trajectory_online.tum  the poses as tracking estimated them frame by frame (before the
                     replacement above)
    lost_predictions.tum  the other frames (RECENTLY_LOST: decaying-velocity prediction; LOST:
                     frozen pose): not estimates, kept apart so no tool scores them by accident
    frames.csv       per frame: state, counts, the inertial state (position sigma, velocity,
                     biases; zero without the IMU) and stage times [ms], also written as it goes
    map.ply          map points (vertices) and map lines (edges between endpoint vertices)
    metrics.json     frames, tracked ratio, median stage times, and ATE/RPE (evo, SE3 alignment,
                     over tracked frames) when the dataset has ground truth; ``completed`` says
                     whether the run finished, else ``stopped_in`` (tracking, map or scoring) and
                     ``stopped_at_frame`` say where it stopped; a failed evaluation is reported
                     as ``evaluation_error``, it never fails the run
    ape.png          the APE plot (with ground truth)
    config.yaml      the configuration used

Interrupts: SIGINT (Ctrl-C) and SIGTERM (``kill``, ``timeout``, containers) stop the frame loop
after the frame in progress; the map and the scores are still written. A further signal stops
that too. Whatever the moment, trajectory.tum holds the frames tracked so far, map.ply is complete
or absent, and metrics.json (written at the start, then replaced) says how far the run got: files
are written under a temporary name and renamed.
"""

from __future__ import annotations

import csv
import dataclasses
import functools
import logging
import os
import signal
import statistics
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from evo.core.trajectory import PoseTrajectory3D

from slslam.config import Config, check_config, default_config, dump_config
from slslam.datasets.euroc import EurocSequence, StereoFrame, is_euroc
from slslam.datasets.kitti import KittiSequence, is_kitti
from slslam.datasets.rosbag import is_rosbag
from slslam.datasets.trajectory_io import tum_lines, tum_time
from slslam.errors import DatasetError, InputError
from slslam.eval.plots import plot_ape
from slslam.eval.report import evaluate, load_groundtruth, write_json
from slslam.progress import progress_bar
from slslam.tracking.tracker import (
    INERTIAL_COUNTS,
    TRACKED_STATES,
    MapData,
    Tracker,
    TrackResult,
)

log = logging.getLogger(__name__)

STAGES = (
    "inference",
    "line_extraction",
    "stereo_matching",
    "matching",
    "optimisation",
    "mapping",
    "relocalisation",
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
    "weighted_inliers",
    "masked_keypoints",
    "imu",
    "position_sigma_m",
    *INERTIAL_COUNTS,
)


@dataclass
class RunSummary:
    """What a run produced: the metrics dictionary (also in metrics.json) and the output folder."""

    out_dir: Path
    metrics: dict
    results: list[TrackResult]


class RunInterrupted(KeyboardInterrupt):
    """A run stopped by SIGINT or SIGTERM; ``signum`` says which (the CLI exits 128 + signum)."""

    def __init__(self, signum: int) -> None:
        self.signum = signum
        super().__init__(f"interrupted by {signal.Signals(signum).name}")


class _Signals:
    """SIGINT and SIGTERM while a run lasts. The handler only counts a signal, unless ``armed()``
    is active, where it raises :class:`RunInterrupted` at once. The frame loop polls with
    :meth:`raise_if_requested` between frames (so the frame in progress is finished and written);
    the map and scoring stages run armed (a signal cuts them short); everything else (closing the
    tracker, writing metrics.json) is never cut: a signal there is noticed by the next check."""

    def __init__(self) -> None:
        self.received: list[int] = []
        self._consumed = 0
        self._armed = False

    def _handler(self, signum: int, frame) -> None:
        self.received.append(signum)
        if self._armed:
            self._consumed = len(self.received)
            raise RunInterrupted(signum)

    def raise_if_requested(self) -> None:
        if len(self.received) > self._consumed:
            self._consumed = len(self.received)
            raise RunInterrupted(self.received[-1])

    @contextmanager
    def armed(self) -> Iterator[None]:
        self._armed = True
        try:
            self.raise_if_requested()
            yield
        finally:
            self._armed = False

    @contextmanager
    def installed(self) -> Iterator[_Signals]:
        """Handle both signals for the duration; the previous handlers come back afterwards.
        Outside the main thread (where Python cannot set handlers) nothing is installed."""
        if threading.current_thread() is not threading.main_thread():
            yield self
            return
        previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
        for s in previous:
            signal.signal(s, self._handler)
        try:
            yield self
        finally:
            for s, handler in previous.items():
                signal.signal(s, handler)


_SIGNALS = threading.local()


def _with_signal_handling(run: Callable) -> Callable:
    """Runs ``run`` with SIGINT and SIGTERM handled (see :class:`_Signals`)."""

    @functools.wraps(run)
    def wrapper(*args, **kwargs):
        with _Signals().installed() as signals:
            _SIGNALS.current = signals
            try:
                return run(*args, **kwargs)
            finally:
                _SIGNALS.current = None

    return wrapper


def _current_signals() -> _Signals:
    return getattr(_SIGNALS, "current", None) or _Signals()


def open_dataset(path: str | Path) -> EurocSequence | KittiSequence:
    """The sequence at ``path``, recognised by its layout: EuRoC ASL (a folder holding mav0/),
    a KITTI odometry sequence (``sequences/NN``) or a KITTI raw drive (``..._sync``)."""
    path = Path(path)
    if not path.exists():
        raise DatasetError(path, "dataset folder not found")
    if is_euroc(path):
        return EurocSequence(path)
    if is_kitti(path):
        return KittiSequence(path)
    if is_rosbag(path):
        raise DatasetError(
            path,
            "a ROS bag: give its image topics and calibration (slslam run BAG --left "
            "TOPIC --right TOPIC --calib YAML; `slslam info BAG` lists the topics)",
        )
    raise DatasetError(
        path,
        "unknown dataset layout: slslam run reads EuRoC ASL folders (the folder holding mav0/, "
        "or mav0 itself), KITTI odometry sequences (sequences/NN with calib.txt, image_0/, "
        "image_1/, times.txt) and KITTI raw drives (image_00/data/, image_01/data/, "
        "calib_cam_to_cam.txt); `slslam sim --out DIR` makes one",
    )


def _frame_stamps_ns(sequence, n: int) -> list[int] | None:
    """The exact timestamps [ns] of the first n frames, when the sequence lists them."""
    stamps = getattr(sequence, "timestamps_ns", None)
    if stamps is None or len(stamps) < n:
        return None
    return [int(t) for t in stamps[:n]]


def _with_frame_rate(config: Config, stamps_ns: list[int] | None) -> Config:
    """``config`` with ``tracking.frame_rate_hz`` taken from the frames' timestamps (one over
    their median interval) where it is 0 (the default) and the sequence lists them."""
    if config.tracking.frame_rate_hz > 0 or stamps_ns is None or len(stamps_ns) < 2:
        return config
    interval_ns = float(np.median(np.diff(np.asarray(stamps_ns, dtype=np.int64))))
    if interval_ns <= 0:
        return config
    tracking = dataclasses.replace(config.tracking, frame_rate_hz=1e9 / interval_ns)
    return dataclasses.replace(config, tracking=tracking)


def _tum_line(result: TrackResult) -> str:
    return tum_lines([tum_time(result.t_ns)], result.T_world_cam)[0]


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
    try:
        _write_ply_body(tmp, vertices, colours, n_points, n_lines)
        tmp.replace(path)
    finally:  # interrupted: no partial file left behind, and never one under the final name
        tmp.unlink(missing_ok=True)
    return path


def _write_ply_body(
    tmp: Path, vertices: np.ndarray, colours: np.ndarray, n_points: int, n_lines: int
) -> None:
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


def tracked_trajectory(results: list[TrackResult]) -> PoseTrajectory3D | None:
    """The tracked frames (OK / NEW_MAP) as an evo trajectory; None when fewer than 2."""
    tracked = [r for r in results if r.state in TRACKED_STATES]
    if len(tracked) < 2:
        return None
    return PoseTrajectory3D(
        poses_se3=[r.T_world_cam for r in tracked],
        timestamps=np.array([r.timestamp for r in tracked]),
    )


def _write_final_trajectory(tracker: Tracker, out: Path) -> PoseTrajectory3D | None:
    """trajectory.tum replaced by the final-map poses (the online file kept as
    trajectory_online.tum); both renames are atomic. None when fewer than 2 poses."""
    final = tracker.final_trajectory()
    if len(final.index) < 2:
        return None
    tmp = out / "trajectory.tum.partial"
    try:
        times = [tum_time(int(t)) for t in final.t_ns]
        with tmp.open("w", encoding="ascii") as f:
            f.writelines(tum_lines(times, final.T_world_cam))
        online = out / "trajectory.tum"
        if online.exists():
            online.replace(out / "trajectory_online.tum")
        tmp.replace(out / "trajectory.tum")
    finally:
        tmp.unlink(missing_ok=True)
    return PoseTrajectory3D(poses_se3=list(final.T_world_cam), timestamps=final.timestamp)


def _score_online(online: PoseTrajectory3D, gt) -> dict:
    """ATE of the online (frame-by-frame) estimate, next to the final one."""
    try:
        evaluation = evaluate(online, gt, align="se3", rpe_delta=None, plot=False)
        return {"ape_online": evaluation.summary()["ape"]}
    except Exception as exc:  # a scoring failure never takes the run down
        return {"ape_online_error": _one_line(exc)}


def _one_line(exc: BaseException, limit: int = 300) -> str:
    text = " ".join(f"{type(exc).__name__}: {exc}".split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _score(estimate: PoseTrajectory3D, gt, out: Path) -> dict:
    """APE (and RPE over 1 m) against ground truth, writing ape.png. A failed evaluation (no
    timestamps in common, a trajectory shorter than the RPE delta, evo failing on a stationary or
    degenerate estimate) is logged as one line and reported as ``evaluation_error``; it does not
    fail the run, whose trajectory is already written. Only the caller writes metrics.json."""
    try:
        try:
            evaluation = evaluate(estimate, gt, align="se3", rpe_delta=1.0, plot=False)
        except InputError as exc:
            log.warning("%s; scoring APE only", exc)
            evaluation = evaluate(estimate, gt, align="se3", rpe_delta=None, plot=False)
    except Exception as exc:  # anything evo or numpy raise: the run's outputs come first
        log.warning("no ATE: %s", _one_line(exc))
        return {"evaluation_error": _one_line(exc)}
    summary = evaluation.summary()
    scores = {k: summary[k] for k in ("ape", "rpe") if k in summary}
    try:  # ATE as a share of the distance driven over the scored span (the drift measure)
        t0, t1 = estimate.timestamps[0], estimate.timestamps[-1]
        inside = (gt.timestamps >= t0) & (gt.timestamps <= t1)
        path = float(np.linalg.norm(np.diff(gt.positions_xyz[inside], axis=0), axis=1).sum())
        scores["path_length_m"] = path
        if path > 0 and "ape" in scores:
            scores["ape_rmse_percent_of_path"] = 100.0 * scores["ape"]["rmse"] / path
    except Exception as exc:
        log.warning("no path length: %s", _one_line(exc))
    try:
        plot_ape(evaluation.ape, out / "ape.png")
    except Exception as exc:
        log.warning("no APE plot: %s", _one_line(exc))
        scores["plot_error"] = _one_line(exc)
    return scores


def _groundtruth(sequence: EurocSequence | KittiSequence, groundtruth: str | Path | None):
    """The ground truth to score against, read and checked before any frame is tracked."""
    if groundtruth is not None:
        if not Path(groundtruth).exists():
            raise DatasetError(groundtruth, "ground-truth file not found")
        # Rectification only rotates the camera: positions in the cam0 and rectified frames agree,
        # so a cam0 ground truth serves the position error (APE translation part) unchanged.
        return load_groundtruth(groundtruth)
    if sequence.groundtruth_path is not None:
        return sequence.groundtruth(frame="rectified")
    return None


def _stereo_frames(sequence: EurocSequence | KittiSequence, n: int) -> Iterator[StereoFrame]:
    """The first n frames (with their exact t_ns), read as they are asked for."""
    for i in range(n):
        yield sequence[i]


def _map_metrics(map_data: MapData) -> dict:
    stats = map_data.stats
    return {
        "keyframes": map_data.keyframes,
        "maps": map_data.maps,
        "map_points": len(map_data.points),
        "map_lines": len(map_data.lines),
        "local_mapping": stats.as_dict(),
        "loops": {
            "detected": stats.loops_detected,
            "accepted": stats.loops_accepted,
            "rejected": stats.loops_rejected,
        },
        "merges": stats.merges,
        "imu": stats.imu
        | (
            {
                "init_after_s": round(
                    (stats.imu["first_init_t_ns"] - stats.imu["first_pose_t_ns"]) / 1e9, 6
                )
            }
            if stats.imu.get("first_init_t_ns") is not None
            else {}
        ),
        "global_ba_runs": stats.global_ba_runs,
        "loop_closing_ms": stats.loop_closing_ms,
        "global_ba_ms": stats.global_ba_ms,
        "global_ba_lock_ms": stats.global_ba_lock_ms,
        "global_ba_cancelled": stats.global_ba_cancelled,
        "welding_ba_runs": stats.welding_ba_runs,
        "welding_ba_ms": stats.welding_ba_ms,
        "loop_events": [dataclasses.asdict(e) for e in stats.loop_events],
    }


#: Front-end class -> its ``features.point_frontend`` name.
_FRONTEND_KEYS: dict[str, Literal["superpoint", "xfeat", "orb"]] = {
    "Orb": "orb",
    "XFeat": "xfeat",
    "SuperPoint": "superpoint",
}


def _dump_effective_config(config: Config, tracker: Tracker, path: Path) -> None:
    """config.yaml as the run used it: the point front end that ran (after a fallback, e.g. to
    ORB when SuperPoint has no weights) and the vocabulary relocalisation loaded, with the
    version in a header."""
    from slslam import __version__, _core

    used = _FRONTEND_KEYS.get(tracker.frontend_name)
    requested = config.features.point_frontend
    features = config.features
    if used is not None and used != requested:
        features = dataclasses.replace(features, point_frontend=used)
    vocabulary = str(tracker.vocabulary) if tracker.vocabulary is not None else None
    tracking = dataclasses.replace(config.tracking, vocabulary_path=vocabulary)
    effective = dataclasses.replace(config, features=features, tracking=tracking)
    lines = [
        f"slslam {__version__} (C++ core {_core.__version__}, commit "
        f"{getattr(_core, '__git_commit__', 'unknown')}): the configuration this run used",
    ]
    if used is None:
        lines.append(f"point front end: {tracker.frontend_name} (given by the caller)")
    elif used != requested:
        lines.append(f"features.point_frontend: {requested} requested, {used} ran")
    if config.tracking.vocabulary_path != vocabulary:
        lines.append(f"tracking.vocabulary_path: {vocabulary or 'none'} (resolved)")
    dump_config(effective, path, header="\n".join(lines))


@_with_signal_handling
def run_sequence(
    dataset: str | Path | EurocSequence,
    out_dir: str | Path,
    config: Config | None = None,
    max_frames: int | None = None,
    progress: bool = True,
    frontend=None,
    groundtruth: str | Path | None = None,
    viewer=None,
    save_map: str | Path | None = None,
    load_map: str | Path | None = None,
    localise_only: bool = False,
) -> RunSummary:
    """Runs the tracker over a sequence and writes the outputs listed in the module docstring.

    Args:
        dataset: the sequence folder (see :func:`open_dataset`), or an opened sequence: an
            ``EurocSequence``, a ``slslam.datasets.rosbag.RosbagSequence`` or anything with
            ``camera``, ``len``, ``sequence[i]`` -> ``StereoFrame`` and ``groundtruth_path``.
        out_dir: output folder, created when missing.
        config: configuration; ``default_config()`` when None (XFeat with its preset).
        max_frames: track only the first N frames.
        progress: show progress (a live bar on a terminal, a line every 10 s in a log).
        frontend: a point front end to use instead of the configured one.
        groundtruth: a ground-truth trajectory file (TUM, EuRoC csv or KITTI, left camera frame)
            used instead of the sequence's own, e.g. for an excerpt that ships none.
        viewer: a :class:`slslam.viz.rerun_log.RerunLogger` shown every frame, the map every
            ``map_every_frames`` frames and the ground truth at the end; a viewer that fails
            is dropped with one warning, the run goes on.
        save_map: write the final atlas there (slslam's binary map file) after the run.
        load_map: start from a saved map file (the first frames relocalise in it).
        localise_only: with ``load_map``, track without changing the map.
    """
    config = config or default_config()
    check_config(config)
    sequence = open_dataset(dataset) if isinstance(dataset, str | os.PathLike) else dataset
    gt = _groundtruth(sequence, groundtruth)  # a bad ground truth fails before any tracking
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(out, "the output folder is an existing file")
    out.mkdir(parents=True, exist_ok=True)
    dump_config(config, out / "config.yaml")
    signals = _current_signals()
    for stale in ("map.ply", "ape.png"):  # left by an earlier run into this folder
        (out / stale).unlink(missing_ok=True)
    # Replaced at the end; until then (even after SIGKILL) it says the run did not complete.
    write_json(
        out / "metrics.json",
        {"dataset": str(dataset), "completed": False, "stopped_in": "tracking"},
    )
    n = len(sequence) if max_frames is None else min(max_frames, len(sequence))
    stamps_ns = _frame_stamps_ns(sequence, n)
    # the options counted in frames follow the camera's rate (tracking.reference_rate_hz)
    config = _with_frame_rate(config, stamps_ns)
    results: list[TrackResult] = []
    error: BaseException | None = None
    with Tracker(
        sequence.camera,
        config,
        frontend=frontend,
        load_map=load_map,
        localise_only=localise_only,
    ) as tracker:
        log.info(
            "tracking %d frames of %s with %s points%s",
            n,
            dataset,
            tracker.frontend_name,
            " + lines" if config.tracking.use_lines else "",
        )
        _dump_effective_config(config, tracker, out / "config.yaml")
        _give_imu(sequence, config, tracker)
        with (
            (out / "trajectory.tum").open("w", encoding="ascii") as traj_file,
            (out / "lost_predictions.tum").open("w", encoding="ascii") as lost_file,
            (out / "frames.csv").open("w", newline="", encoding="ascii") as frames_file,
        ):
            writer = csv.writer(frames_file)
            writer.writerow(["index", "timestamp", "state", *COUNTS, *(f"{s}_ms" for s in STAGES)])
            # The front end reads and prepares frame k+1 while the core tracks frame k
            # (tracking.pipeline; Tracker.track_stream).
            stream = tracker.track_stream(
                _stereo_frames(sequence, n), pipeline=config.tracking.pipeline
            )
            bar = progress_bar(stream, desc="tracking", unit="frame", enabled=progress, total=n)
            try:
                for result in bar:
                    results.append(result)
                    pose_file = traj_file if result.state in TRACKED_STATES else lost_file
                    pose_file.write(_tum_line(result))
                    pose_file.flush()
                    writer.writerow(
                        [
                            result.index,
                            tum_time(result.t_ns),
                            result.state,
                            *(getattr(result.counts, c) for c in COUNTS),
                            *(f"{getattr(result.timings_ms, s):.3f}" for s in STAGES),
                        ]
                    )
                    frames_file.flush()
                    viewer = _show(viewer, _show_frame, tracker, result)
                    bar.set_postfix(
                        state=result.state, pts=result.counts.inlier_points, refresh=False
                    )
                    signals.raise_if_requested()  # SIGINT / SIGTERM: stop between frames
            except (Exception, KeyboardInterrupt) as exc:  # keep what was tracked
                error = exc
                log.error(
                    "run stopped at frame %d: %s; writing the map and metrics so far",
                    len(results),
                    exc,
                )
            finally:
                stream.close()  # the front-end worker stops after the frame it is preparing
    # After the frame loop: the map, then the scores. An error or a signal in one of them skips
    # what is left; metrics.json is written in every case and says where the run stopped.
    stops: list[tuple[str, BaseException]] = [] if error is None else [("tracking", error)]
    map_data: MapData | None = None

    final: PoseTrajectory3D | None = None

    def map_stage() -> None:
        nonlocal map_data, final
        map_data = tracker.map()
        write_ply(out / "map.ply", map_data.points, map_data.lines)
        final = _write_final_trajectory(tracker, out)
        if save_map is not None:
            tracker.save_map(save_map)

    _stage("map", map_stage, signals, stops, out)
    online = tracked_trajectory(results)
    estimate = final if final is not None else online
    scores: dict = {}
    if estimate is not None and gt is not None:
        _stage("scoring", lambda: scores.update(_score(estimate, gt, out)), signals, stops, out)
        if final is not None and online is not None and "ape" in scores:
            # the online estimate too, so the effect of loop closing shows in one run
            _stage(
                "scoring",
                lambda: scores.update(_score_online(online, gt)),
                signals,
                stops,
                out,
            )
    elif gt is not None:
        scores["evaluation_error"] = "fewer than 2 tracked frames: nothing to score"

    tracked = sum(r.state in TRACKED_STATES for r in results)
    metrics: dict = {
        "completed": not stops,
        "dataset": str(dataset),
        "frontend": tracker.frontend_name,
        "lines": config.tracking.use_lines,
        "frames": len(results),
        "tracked_frames": tracked,
        "tracked_ratio": tracked / len(results) if results else 0.0,
        "states": {
            s: sum(r.state == s for r in results) for s in sorted({r.state for r in results})
        },
        **_loss_metrics(results),
        "rig_adapted": tracker.rig_adapted_options(),
        "median_ms": {
            s: statistics.median(getattr(r.timings_ms, s) for r in results) if results else None
            for s in STAGES
        },
    }
    if map_data is not None:
        metrics.update(_map_metrics(map_data))
    metrics.update(scores)
    if stops:
        metrics["stopped_in"], first = stops[0]
        metrics["stopped_at_frame"] = len(results)
        metrics["error"] = _one_line(first)
        if len(stops) > 1:  # a second signal (or error) while finishing
            metrics["finishing_stopped_in"] = stops[1][0]
    viewer = _show(viewer, _show_end, map_data, estimate, gt, metrics)
    write_json(out / "metrics.json", metrics)
    if stops:
        raise stops[-1][1] if isinstance(stops[-1][1], KeyboardInterrupt) else stops[0][1]
    return RunSummary(out, metrics, results)


def _give_imu(sequence, config: Config, tracker: Tracker) -> None:
    """The sequence's IMU samples to the tracker (``tracking.imu``), when it has any."""
    if not config.tracking.imu.enabled or not callable(getattr(sequence, "imu", None)):
        return
    if getattr(sequence, "has_imu", True) is False:  # a bag run without an IMU topic
        log.info("no IMU topic in %s: camera only", sequence)
        return
    imu_csv = getattr(sequence, "root", Path(".")) / "imu0" / "data.csv"
    if isinstance(sequence, EurocSequence) and not imu_csv.is_file():
        log.info("no IMU samples (%s): camera only", imu_csv)
        return
    samples = sequence.imu()
    t_ns = np.asarray(samples["t_ns"], dtype=np.int64)
    tracker.add_imu(t_ns, samples["gyro"], samples["acc"])
    if len(t_ns) > 1:
        rate = (len(t_ns) - 1) / ((int(t_ns[-1]) - int(t_ns[0])) / 1e9)
        log.info(
            "IMU: %d samples at %.0f Hz, coupled into tracking (tracking.imu)", len(t_ns), rate
        )


def _show(viewer, show: Callable, *args):
    """``show(viewer, *args)``; the viewer, or None once it failed (logged once)."""
    if viewer is None:
        return None
    try:
        show(viewer, *args)
    except Exception as exc:  # a viewer never stops a run
        log.warning("viewer stopped: %s", _one_line(exc))
        return None
    return viewer


def _show_frame(viewer, tracker: Tracker, result: TrackResult) -> None:
    viewer.log_frame(result, tracker.last_image, tracker.last_keypoints_uv)
    if viewer.wants_map(result.index):
        viewer.log_map(tracker.map(settle=False))  # a snapshot: the run's poses stay the same


def _show_end(viewer, map_data: MapData | None, estimate, gt, metrics: dict) -> None:
    if map_data is not None:
        viewer.log_map(map_data)
    if estimate is not None and gt is not None:
        viewer.log_groundtruth(estimate, gt)
    viewer.log_metrics(metrics)


def _loss_metrics(results: list[TrackResult]) -> dict:
    """Losses and recoveries: frames posed after the first initialisation, relocalisations, maps
    started after a loss, frames and seconds spent without an estimate."""
    first = next((i for i, r in enumerate(results) if r.state != "NOT_INITIALIZED"), None)
    if first is None:
        return {"posed_ratio_after_init": 0.0, "relocalisations": 0, "lost_frames": 0}
    after = results[first:]
    unposed = [r for r in after if r.state not in TRACKED_STATES]
    # A frame without an estimate lasts until the next frame's timestamp (the median step at the
    # end of the run).
    steps = np.diff([r.timestamp for r in results])
    step = float(np.median(steps)) if len(steps) else 0.0
    stamps = {r.index: r.timestamp for r in results}
    lost_s = sum(stamps.get(r.index + 1, r.timestamp + step) - r.timestamp for r in unposed)
    return {
        "posed_ratio_after_init": sum(r.state in TRACKED_STATES for r in after) / len(after),
        "relocalisations": sum(r.state == "RELOCALISED" for r in after),
        # frames the IMU carried through a visual outage (posed, state INERTIAL)
        "inertial_frames": sum(r.state == "INERTIAL" for r in after),
        "new_maps_after_loss": sum(r.state == "NEW_MAP" for r in after),
        "lost_frames": len(unposed),
        "lost_s": round(lost_s, 6),
    }


#: Tests only: ``SLSLAM_TEST_PAUSE_IN=map`` (or ``scoring``) makes that stage write
#: ``<out>/paused_in_<stage>`` and wait up to 60 s, so a test can signal the run at that moment.
TEST_PAUSE_ENV = "SLSLAM_TEST_PAUSE_IN"


def _pause_for_tests(stage: str, out: Path) -> None:
    if os.environ.get(TEST_PAUSE_ENV) == stage:
        (out / f"paused_in_{stage}").touch()
        time.sleep(60)  # a signal ends the sleep: the handler raises


def _stage(
    name: str,
    work: Callable[[], None],
    signals: _Signals,
    stops: list[tuple[str, BaseException]],
    out: Path,
) -> None:
    """Runs one stage after the frame loop, armed for signals; an error or a signal is recorded
    in ``stops``. Skipped when a stage before it (after the frame loop) was stopped."""
    if any(stage != "tracking" for stage, _ in stops):
        return
    try:
        with signals.armed():
            _pause_for_tests(name, out)
            work()
    except (Exception, KeyboardInterrupt) as exc:
        log.error("run stopped in the %s stage: %s", name, _one_line(exc))
        stops.append((name, exc))
