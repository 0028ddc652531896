"""A run as a rerun recording (``rerun-sdk``): live in the viewer, or an ``.rrd`` file for later.

``slslam run ... --viewer`` spawns the rerun viewer and streams to it; ``--rerun FILE.rrd`` saves
the recording (``rerun FILE.rrd`` opens it). Both can be given. Entities (timelines ``frame``,
the frame index, and ``time``, seconds since the first frame):

=================================  ===========================================================
``world``                          the map frame (the first camera's: x right, y down, z ahead)
``world/camera``                   ``T_world_cam`` of the left camera, every frame (a
                                   prediction while lost)
``world/camera/image``             pinhole model and the rectified left image (JPEG)
``world/camera/image/keypoints``   the keypoints the tracker used, coloured by the frame's state
``world/camera/image/lines``       the frame's LSD segments (the tracker's extractor and
                                   preprocessing, re-run for display), coloured by state
``world/trajectory``               the estimated path (frames with an estimated pose)
``world/keyframes``                positions of the frames that became keyframes
``world/map/points``, ``world/map/lines``   the sparse map, every ``map_every_frames`` frames
                                   and at the end
``world/groundtruth``              the ground truth over the estimated span, moved into the map
                                   frame by an SE3 Umeyama alignment onto the estimate, at the end
``state``                          the frame's state as a text log (colour as below)
``timings/<stage>``                per-stage times [ms] as plots
``counts/<name>``                  inlier points, inlier lines, keypoints as plots
=================================  ===========================================================

State colours: OK green, RELOCALISED blue, NEW_MAP purple, INERTIAL cyan, RECENTLY_LOST orange,
LOST red, NOT_INITIALIZED grey. Per-feature inlier flags are not exported by the C++ tracker yet,
so a feature takes its frame's colour.
"""

from __future__ import annotations

import logging
import os
import sys
from collections.abc import Mapping
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)

STATE_COLOURS: dict[str, tuple[int, int, int]] = {
    "OK": (40, 200, 40),
    "RELOCALISED": (30, 120, 255),
    "NEW_MAP": (170, 60, 255),
    "INERTIAL": (0, 200, 200),
    "RECENTLY_LOST": (255, 165, 0),
    "LOST": (230, 30, 30),
    "NOT_INITIALIZED": (150, 150, 150),
}
TRACKED = ("OK", "RELOCALISED", "NEW_MAP", "INERTIAL")
COUNT_PLOTS = ("keypoints", "inlier_points", "inlier_lines")


def _has_display() -> bool:
    """Whether a spawned viewer can open a window: on Linux an X11 or Wayland display is set."""
    if not sys.platform.startswith("linux"):
        return True
    return any(os.environ.get(k) for k in ("DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"))


VIEWER_TIMEOUT_S = 5.0  # how long a spawned viewer may take to accept the first data


class RerunLogger:
    """Logs frames, the map and trajectories of a run to a rerun recording.

    Args:
        camera: the rectified stereo camera (``fx, fy, cx, cy, width, height``).
        recording: an ``.rrd`` file to save to (None: no file).
        spawn: start the rerun viewer and stream to it.
        jpeg_quality: JPEG quality of the logged images (0 logs no images).
        lines: log the frame's line segments (re-extracted for display: costs an LSD per frame).
        map_every_frames: log the map every N frames during the run (0: only at the end).
    """

    def __init__(
        self,
        camera,
        recording: str | Path | None = None,
        spawn: bool = False,
        jpeg_quality: int = 75,
        lines: bool = True,
        map_every_frames: int = 20,
        application_id: str = "slslam",
    ) -> None:
        import rerun as rr

        if recording is None and not spawn:
            raise ValueError("RerunLogger needs a recording file, spawn=True, or both")
        if not 0 <= jpeg_quality <= 100:
            raise ValueError(f"jpeg_quality {jpeg_quality} not in [0, 100]")
        self._rr = rr
        self.rec = rr.RecordingStream(application_id)
        path = None if recording is None else Path(recording)
        if path is not None:
            if path.suffix != ".rrd":
                raise ValueError(f"{path}: a rerun recording file ends in .rrd")
            path.parent.mkdir(parents=True, exist_ok=True)
        self.camera = camera
        self.jpeg_quality = jpeg_quality
        self.lines = lines
        self.map_every_frames = map_every_frames
        self._t0: float | None = None
        self._path: list[np.ndarray] = []
        self._keyframes: list[np.ndarray] = []
        file_sink = [] if path is None else [rr.FileSink(str(path))]
        if spawn and not _has_display():
            # The viewer would start its server, accept some data and die when it cannot open a
            # window: whether a flush sees it alive is a race, so do not spawn it at all.
            reason = "no display: DISPLAY and WAYLAND_DISPLAY are unset"
            if path is None:
                raise ValueError(f"the rerun viewer is not reachable ({reason})")
            log.warning(
                "the rerun viewer is not reachable (%s); recording to %s only", reason, path
            )
            spawn = False
        if spawn:
            self.rec.spawn(connect=False)
            self.rec.set_sinks(*file_sink, rr.GrpcSink())
            self._log_static()
            try:  # a viewer that cannot open a window (no display) is gone by now
                self.rec.flush(timeout_sec=VIEWER_TIMEOUT_S)
                return
            except RuntimeError as exc:
                if path is None:
                    raise ValueError(f"the rerun viewer is not reachable ({exc})") from None
                log.warning("the rerun viewer is not reachable; recording to %s only", path)
        self.rec.set_sinks(*file_sink)
        self._log_static()

    def _log_static(self) -> None:
        rr, cam = self._rr, self.camera
        self.rec.log("world", rr.ViewCoordinates.RDF, static=True)
        self.rec.log(
            "world/camera/image",
            rr.Pinhole(
                focal_length=[cam.fx, cam.fy],
                principal_point=[cam.cx, cam.cy],
                width=cam.width,
                height=cam.height,
                camera_xyz=rr.ViewCoordinates.RDF,
                image_plane_distance=0.3,
            ),
            static=True,
        )

    def _set_time(self, index: int, timestamp: float) -> None:
        if self._t0 is None:
            self._t0 = timestamp
        self.rec.set_time("frame", sequence=index)
        self.rec.set_time("time", duration=timestamp - self._t0)

    def log_frame(
        self,
        result,
        image: np.ndarray | None = None,
        keypoints_uv: np.ndarray | None = None,
    ) -> None:
        """One frame: pose, image, keypoints, lines, state, timings and counts. ``result`` is a
        :class:`~slslam.tracking.tracker.TrackResult`; ``image`` the rectified left image."""
        rr = self._rr
        self._set_time(result.index, result.timestamp)
        colour = STATE_COLOURS.get(result.state, (255, 255, 255))
        T = np.asarray(result.T_world_cam)
        self.rec.log("world/camera", rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]))
        self.rec.log("state", rr.TextLog(result.state, color=colour))
        if result.state in TRACKED:
            self._path.append(T[:3, 3].copy())
            self.rec.log("world/trajectory", rr.LineStrips3D([np.array(self._path)]))
            if result.counts.keyframe:
                self._keyframes.append(T[:3, 3].copy())
                self.rec.log(
                    "world/keyframes",
                    rr.Points3D(np.array(self._keyframes), colors=(255, 200, 0), radii=0.03),
                )
        if image is not None and self.jpeg_quality > 0:
            self.rec.log(
                "world/camera/image",
                rr.Image(image).compress(jpeg_quality=self.jpeg_quality),
            )
            if self.lines:
                self._log_lines(image, colour)
        if keypoints_uv is not None:
            self.rec.log(
                "world/camera/image/keypoints",
                rr.Points2D(np.asarray(keypoints_uv).reshape(-1, 2), colors=colour, radii=1.5),
            )
        for stage, ms in result.timings_ms.as_dict().items():
            self.rec.log(f"timings/{stage}", rr.Scalars(float(ms)))
        for name in COUNT_PLOTS:
            self.rec.log(f"counts/{name}", rr.Scalars(float(getattr(result.counts, name))))

    def _log_lines(self, image: np.ndarray, colour) -> None:
        from slslam import _core

        segments = np.asarray(_core.extract_lines(image)[0]).reshape(-1, 4)
        self.rec.log(
            "world/camera/image/lines",
            self._rr.LineStrips2D(segments.reshape(-1, 2, 2), colors=colour, radii=0.8),
        )

    def wants_map(self, index: int) -> bool:
        """True on the frames where the map should be logged during the run."""
        return self.map_every_frames > 0 and index > 0 and index % self.map_every_frames == 0

    def log_map(self, map_data) -> None:
        """The sparse map (``MapData``: points (N, 3), lines (M, 6)) at the current time."""
        rr = self._rr
        points = np.asarray(map_data.points).reshape(-1, 3)
        lines = np.asarray(map_data.lines).reshape(-1, 2, 3)
        self.rec.log("world/map/points", rr.Points3D(points, colors=(200, 200, 200), radii=0.01))
        self.rec.log("world/map/lines", rr.LineStrips3D(lines, colors=(255, 140, 0), radii=0.005))

    def log_groundtruth(self, estimate, groundtruth) -> None:
        """The ground truth in the map frame: the poses matched to the estimate's timestamps
        (evo), aligned onto the estimate by SE3 Umeyama (rigid: the inverse of ATE's alignment)."""
        from evo.core import sync

        gt, est = sync.associate_trajectories(groundtruth, estimate, max_diff=0.01)
        if est.num_poses < 3:
            log.warning("rerun: fewer than 3 ground-truth poses match the estimate; not logged")
            return
        gt.align(est, correct_scale=False)  # gt is a synchronised copy: aligned in place
        self.rec.log(
            "world/groundtruth",
            self._rr.LineStrips3D([gt.positions_xyz], colors=(255, 0, 255), radii=0.01),
            static=True,
        )

    def log_metrics(self, metrics: Mapping) -> None:
        """The run's summary as a text entry (tracked ratio, ATE)."""
        parts = [f"tracked {metrics.get('tracked_ratio', 0):.3f}"]
        if "ape" in metrics:
            parts.append(f"ATE RMSE {metrics['ape']['rmse']:.4f} m")
        self.rec.log("summary", self._rr.TextLog(", ".join(parts)), static=True)

    def close(self) -> None:
        """Flushes the recording (the .rrd file is complete afterwards); a viewer that went away
        is reported, not raised."""
        try:
            self.rec.flush()
        except RuntimeError as exc:
            log.warning("rerun viewer: %s", exc)
        self.rec.disconnect()

    def __enter__(self) -> RerunLogger:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
