"""``slslam.Tracker``: stereo point-line SLAM on rectified image pairs.

Python runs the point network (SuperPoint through onnxruntime, or ORB) and the per-cell limit (C++);
line extraction, stereo matching, tracking, motion-only BA and local mapping run in the C++ core
with the GIL released.

    with slslam.Tracker(camera, config) as tracker:
        for frame in sequence:
            result = tracker.track(frame.left, frame.right, t_ns=frame.t_ns)
        stamps, poses, states = tracker.trajectory()
        cloud = tracker.map()

Frame pipeline (``Tracker.track_stream``): a worker thread reads the next frames and runs the
point front end on them (onnxruntime and the C++ ORB release the GIL) while the C++ core tracks
frame k. The hand-over holds ``tracking.pipeline_frames_ahead`` frames (default 3): the worker
reads a frame only while fewer than that wait for the core, so the queue is bounded and the
poses are the same as ``track`` in a loop (the front end has no state from frame to frame). With
more than one the front end goes on through a keyframe's inline local mapping instead of
waiting for it. The threads (that worker, and the right image's and the lines' helpers of each
frame) are in ``slslam.tracking.pipeline``; this module gives them the work.
"""

from __future__ import annotations

import dataclasses
import logging
import numbers
import time
import warnings
from collections.abc import Generator, Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from contextlib import closing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol, cast

import numpy as np

from slslam import _core
from slslam.config import (
    DYNAMIC_CELLS_TO_CORE,
    IMU_TO_CORE,
    LINES_TO_CORE,
    LOOP_CLOSING_TO_CORE,
    TRACKING_TO_CORE,
    Config,
    default_config,
    make_point_frontend,
)
from slslam.datasets.euroc import RectifiedStereoCamera
from slslam.datasets.images import GrayImageReader
from slslam.errors import InputError, SlslamError
from slslam.features.frontend import PointFrontEnd, frontend_capabilities
from slslam.features.keypoints import Keypoints, check_gray_image
from slslam.features.low_light import LowLightEnhancer
from slslam.timestamps import (
    INT64_MAX,
    INT64_MIN,
    ns_from_seconds,
    seconds_from_ns,
    seconds_from_ns_array,
)
from slslam.tracking.pipeline import FrontEndThreads, run_ahead

log = logging.getLogger(__name__)

#: Per-frame states. Estimated poses: OK (tracked), RELOCALISED (found again in a map by bag of
#: words after a loss), NEW_MAP (a new map started after a loss, anchored at the frozen pose).
#: No estimate: RECENTLY_LOST (the pose is a prediction with a decaying velocity), LOST (the pose
#: is frozen at the last prediction), NOT_INITIALIZED (no map yet).
STATES = (
    "NOT_INITIALIZED",
    "OK",
    "LOST",
    "NEW_MAP",
    "RECENTLY_LOST",
    "RELOCALISED",
    "INERTIAL",
)
TRACKED_STATES = ("OK", "NEW_MAP", "RELOCALISED", "INERTIAL")


class _FieldsAsMapping:
    """Read access by key (``counts["inlier_points"]``), the dict interface these results had
    before they were typed; deprecated for one release in favour of attributes."""

    def as_dict(self) -> dict[str, Any]:
        """The fields by name, in declaration order."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}  # type: ignore[arg-type]

    def _warn(self) -> None:
        warnings.warn(
            f"{type(self).__name__}[key] is deprecated: use attributes or as_dict()",
            DeprecationWarning,
            stacklevel=3,
        )

    def __getitem__(self, key: str) -> Any:
        self._warn()
        if key not in self.as_dict():
            raise KeyError(key)
        return getattr(self, key)

    def get(self, key: str, default: Any = None) -> Any:
        self._warn()
        return self.as_dict().get(key, default)

    def items(self) -> Iterator[tuple[str, Any]]:
        self._warn()
        return iter(self.as_dict().items())

    def __contains__(self, key: object) -> bool:
        return key in self.as_dict()


@dataclass(frozen=True)
class StageTimings(_FieldsAsMapping):
    """Wall time of one frame's stages [ms]. ``total`` is the frame's own work (front end plus
    core); in the pipeline (``track_stream``) stages of neighbouring frames overlap."""

    inference: float = 0.0  #: point front end (network or ORB) on both images
    line_extraction: float = 0.0  #: line detection and descriptors (left image, on a thread
    #: beside ``inference``; both images in the core with ``right_lines_on_keyframes: false``)
    stereo_matching: float = 0.0  #: left-right point and line matching
    matching: float = 0.0  #: local-map projection and guided matching
    optimisation: float = 0.0  #: motion-only bundle adjustment
    mapping: float = 0.0  #: keyframe insertion (the right image's lines for it, + local
    #: mapping in sequential mode)
    relocalisation: float = 0.0  #: BoW query, PnP and local-map tracking while lost
    total: float = 0.0  #: the frame's own work (wall: the front end's steps side by side)


@dataclass(frozen=True)
class FrameCounts(_FieldsAsMapping):
    """What one frame found and kept."""

    keypoints: int = 0  #: left-image keypoints after the grid limit
    lines: int = 0  #: left-image line segments
    matched_points: int = 0  #: guided point matches before optimisation
    inlier_points: int = 0  #: point inliers of the motion-only BA
    matched_lines: int = 0  #: guided line matches before optimisation
    inlier_lines: int = 0  #: line inliers of the motion-only BA
    keyframe: int = 0  #: 1 when a keyframe was made from this frame, else 0
    map: int = -1  #: index of the atlas map the pose belongs to (-1: none)
    weighted_inliers: float = 0.0  #: point inliers + line weight x line inliers
    masked_keypoints: int = 0  #: keypoints in cells the dynamic-cell filter masked
    #: 1 when tracked on keypoints projected from the map (tracking.projected_max_frames): the
    #: point front end did not run on it, ``keypoints`` counts the projected ones; else 0
    projected: int = 0
    imu: int = 0  #: 1 when the inertial state existed after the frame (IMU initialised), else 0
    position_sigma_m: float = 0.0  #: its position standard deviation then [m] (0: no IMU)
    #: the inertial state after the frame (0 without it): the body's velocity in the world
    #: [m/s] and the IMU biases in the body frame (accelerometer [m/s^2], gyroscope [rad/s])
    v_world_x_mps: float = 0.0
    v_world_y_mps: float = 0.0
    v_world_z_mps: float = 0.0
    acc_bias_x_mps2: float = 0.0
    acc_bias_y_mps2: float = 0.0
    acc_bias_z_mps2: float = 0.0
    gyro_bias_x_radps: float = 0.0
    gyro_bias_y_radps: float = 0.0
    gyro_bias_z_radps: float = 0.0


@dataclass
class TrackResult:
    """The outcome of one frame.

    Attributes:
        index: input frame number (0-based).
        t_ns: capture time [ns] as given (``timestamp`` is it in float seconds).
        state: one of ``STATES``.
        T_world_cam: 4x4 pose of the left camera in the world (map) frame (``T_wc`` is a
            deprecated alias, kept for one release).
        timings_ms: per-stage wall times (:class:`StageTimings`).
        counts: keypoints, lines, matches, inliers, keyframe, map (:class:`FrameCounts`).
    """

    index: int
    t_ns: int
    state: str
    T_world_cam: np.ndarray
    timings_ms: StageTimings = field(default_factory=StageTimings)
    counts: FrameCounts = field(default_factory=FrameCounts)

    @property
    def timestamp(self) -> float:
        """The capture time in seconds (:func:`slslam.timestamps.seconds_from_ns`)."""
        return seconds_from_ns(self.t_ns)

    @property
    def tracked(self) -> bool:
        return self.state in TRACKED_STATES

    @property
    def T_wc(self) -> np.ndarray:
        """Deprecated alias of :attr:`T_world_cam` (removed in the release after 0.1)."""
        warnings.warn(
            "TrackResult.T_wc is deprecated: use T_world_cam", DeprecationWarning, stacklevel=2
        )
        return self.T_world_cam


#: FrameCounts' inertial fields, per vector of the core's FrameOutput: the fields' prefix, the
#: FrameOutput attribute, the unit suffix and the digits kept
_INERTIAL_VECTORS = (
    ("v_world", "v_world_body", "mps", 5),
    ("acc_bias", "acc_bias", "mps2", 6),
    ("gyro_bias", "gyro_bias", "radps", 8),
)
#: their names, x y z of each vector (frames.csv's columns)
INERTIAL_COUNTS = tuple(f"{p}_{a}_{unit}" for p, _, unit, _ in _INERTIAL_VECTORS for a in "xyz")


def _inertial_columns(out: _core.FrameOutput) -> dict[str, float]:
    """FrameCounts' inertial fields from the core's velocity and bias vectors."""
    columns: dict[str, float] = {}
    for prefix, attribute, unit, digits in _INERTIAL_VECTORS:
        vector = np.asarray(getattr(out, attribute), dtype=float).reshape(3)
        for axis, value in zip("xyz", vector, strict=True):
            columns[f"{prefix}_{axis}_{unit}"] = round(float(value), digits)
    return columns


class SupportsStereoFrame(Protocol):
    """A rectified stereo frame with its exact time, as the readers' ``StereoFrame``."""

    @property
    def left(self) -> np.ndarray: ...
    @property
    def right(self) -> np.ndarray: ...
    @property
    def t_ns(self) -> int: ...


def _unpack_frame(
    frame: tuple[np.ndarray, np.ndarray, float] | SupportsStereoFrame,
) -> tuple[np.ndarray, np.ndarray, float | None, int | None]:
    """(left, right, seconds, t_ns) of a track_stream item: a (left, right, timestamp [s])
    triple, or a frame with ``left``, ``right`` and ``t_ns``."""
    if isinstance(frame, tuple):
        left, right, seconds = frame
        return left, right, seconds, None
    return frame.left, frame.right, None, frame.t_ns


def _frame_time_ns(where: str, timestamp: float | None, t_ns: int | None) -> int:
    """The frame's time [ns] from exactly one of float seconds and integer nanoseconds; bad
    values raise ``InputError`` naming the frame."""
    if (timestamp is None) == (t_ns is None):
        raise InputError(where, "give the frame's time as timestamp [s] or t_ns [ns], once")
    if t_ns is not None:
        if isinstance(t_ns, bool) or not isinstance(t_ns, numbers.Integral):
            raise InputError(where, f"t_ns must be an integer [ns], got {t_ns!r}")
        if not INT64_MIN <= int(t_ns) <= INT64_MAX:
            raise InputError(where, f"t_ns {t_ns} does not fit int64 nanoseconds")
        return int(t_ns)
    try:
        return ns_from_seconds(cast(float, timestamp))
    except (TypeError, ValueError):
        raise InputError(
            where, f"timestamp {timestamp} s is not finite or beyond int64 nanoseconds"
        ) from None


@dataclass
class _Prepared:
    """A checked frame with its keypoints and stereo matching, ready for the core (the images,
    keypoints and lines the core needs travel inside ``stereo``)."""

    index: int
    t_ns: int
    left: np.ndarray  #: as the core saw it (the viewer's last image)
    left_keypoints: Keypoints
    inference_ms: float  #: point front end, both images (wall)
    front_ms: float  #: the whole front-end step (wall): points, lines, stereo matching
    stereo: _core.PreparedFrame  #: TrackerCore.prepare's frame: what the core tracks
    raw_left: np.ndarray  #: the checked gray images as given (to detect keypoints on later)
    raw_right: np.ndarray
    lines: Future | None  #: the left image's lines extracted beside it (reused when redone)


@dataclass(frozen=True)
class LoopEvent:
    """One accepted loop or map merge, by the input frames of the two keyframes it joined."""

    frame_index: int  #: input frame of the keyframe that closed it
    candidate_frame_index: int  #: input frame of the older keyframe it matched
    merge: bool  #: maps merged (else a loop within one map)
    correction_m: float  #: how far the keyframe moved [m] (0 for a merge: two worlds)


@dataclass(frozen=True)
class MapStats:
    """Counters of local mapping, relocalisation and loop closing over a run (times in ms)."""

    keyframes_processed: int = 0
    keyframes_culled: int = 0
    points_triangulated: int = 0
    lines_triangulated: int = 0
    points_culled: int = 0
    lines_culled: int = 0
    local_mapping_ms: float = 0.0  #: local mapping in all (triangulation, local BA, culling)
    local_ba_interrupted: int = 0  #: local BAs a newer keyframe stopped early (threaded mapping)
    local_ba_solve_ms: float = 0.0  #: of local_mapping_ms, the local BAs' solves (Ceres)
    #: the local BAs' trust-region steps (both passes; 5 + 10 at most each by default) and, of
    #: them, those rejected because the cost rose (a rejected step costs a linear solve too)
    local_ba_iterations: int = 0
    local_ba_rejected_steps: int = 0
    local_ba_inertial_factors: int = 0  #: IMU factors between keyframes (imu.local_ba_keyframes)
    relocalisations: int = 0
    relocalisation_attempts: int = 0
    maps_started: int = 0
    #: maps resumed at the IMU's pose after a loss, no new one started
    #: (tracking.imu.resume_map_after_lost)
    maps_resumed: int = 0
    inertial_frames: int = 0  #: frames whose pose the IMU carried (state INERTIAL)
    inertial_weak_updates: int = 0  #: ... of them corrected by a weak visual pose
    inertial_keyframes: int = 0  #: ... of them made keyframes (tracking.imu.keyframe_interval_s)
    line_frames: int = 0  #: frames whose left lines were extracted (all, unless lines_on_demand)
    loop_keyframes_checked: int = 0
    loop_candidates_verified: int = 0
    loops_detected: int = 0  #: verified and plausible hypotheses (before consistency)
    loops_rejected: int = 0  #: implausible (drift gate) or inconsistent
    loops_accepted: int = 0  #: loops closed within a map
    merges: int = 0  #: maps merged into an older one
    merges_in_yaw_and_position: int = 0  #: ... of them turned about gravity only (both had it)
    global_ba_runs: int = 0  #: finished global bundle adjustments
    loop_closing_ms: float = 0.0  #: detection, verification, correction
    global_ba_ms: float = 0.0  #: build, solve and write back of the finished global BAs
    global_ba_lock_ms: float = 0.0  #: of which the map was locked (the rest ran beside tracking)
    global_ba_cancelled: int = 0  #: background global BAs a newer loop or merge cancelled
    welding_ba_runs: int = 0  #: welding BAs over the seam of a merge
    welding_ba_ms: float = 0.0  #: their build, solve and write back
    loop_events: tuple[LoopEvent, ...] = ()
    #: the IMU: has_imu, initialised, first_pose_t_ns and first_init_t_ns (camera time [ns], None:
    #: never), initialisations, refinements, rejected_refinements, last_failure,
    #: nonholonomic_updates (blind frames held to the axis of travel), zero_velocity_updates
    #: (blind frames held at rest), flow_updates (blind frames given the optical flow's
    #: velocity), travel_side_ratio (RMS
    #: side speed over speed while tracked; -1: not measured), gyro_bias_radps, acc_bias_mps2,
    #: g_world_mps2
    imu: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        """Plain values (loop events as dicts), e.g. for metrics.json."""
        return dataclasses.asdict(self) | {
            "loop_events": [dataclasses.asdict(e) for e in self.loop_events]
        }

    # Deprecated dict-style access (MapData.stats was a dict up to 0.1): for one release.
    def __getitem__(self, key: str) -> Any:
        warnings.warn(
            "MapData.stats[key] is deprecated: use the attribute (stats.key)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.as_dict()[key]

    def get(self, key: str, default: Any = None) -> Any:
        """Deprecated: use the attribute."""
        warnings.warn(
            "MapData.stats.get(key) is deprecated: use the attribute (stats.key)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.as_dict().get(key, default)


@dataclass
class MapData:
    """Sparse map: ``points`` (N, 3) and ``lines`` (M, 6: start xyz, end xyz) in metres, the
    number of keyframes and maps, and the run's counters (``stats``)."""

    points: np.ndarray
    lines: np.ndarray
    keyframes: int
    maps: int
    stats: MapStats = field(default_factory=MapStats)


@dataclass(frozen=True)
class FinalTrajectory:
    """Estimated frame poses in the final map (see :meth:`Tracker.final_trajectory`): per frame its
    ``index``, ``t_ns`` [ns] (``timestamp`` in seconds), ``map_index`` (after merges) and
    ``T_world_cam`` (N, 4, 4)."""

    index: np.ndarray
    t_ns: np.ndarray
    map_index: np.ndarray
    T_world_cam: np.ndarray

    @property
    def timestamp(self) -> np.ndarray:
        """The capture times in seconds (:func:`slslam.timestamps.seconds_from_ns`)."""
        return seconds_from_ns_array(self.t_ns)


def _set_core(options: Any, path: str, value: Any) -> None:
    *parents, last = path.split(".")
    target = options
    for part in parents:
        target = getattr(target, part)
    setattr(target, last, value)


def _line_options(config: Config) -> _core.LineExtractorOptions:
    """The line front end's options from the tracking section (LINES_TO_CORE)."""
    options = _core.LineExtractorOptions()
    for name, paths in LINES_TO_CORE.items():
        for path in paths:
            _set_core(options, path, getattr(config.tracking, name))
    try:
        options.check()
    except ValueError as exc:
        raise InputError("tracking config", str(exc)) from exc
    return options


def _core_options(
    camera: RectifiedStereoCamera, config: Config, vocabulary: Path | None = None
) -> _core.TrackerOptions:
    t = config.tracking
    pinhole = _core.PinholeCamera(
        camera.fx, camera.fy, camera.cx, camera.cy, camera.width, camera.height
    )
    options = _core.TrackerOptions()
    options.rig = _core.StereoRig(pinhole, camera.baseline_m)
    for section, table in (
        (t, TRACKING_TO_CORE),
        (t.loop_closing, LOOP_CLOSING_TO_CORE),
        (t.imu, IMU_TO_CORE),
        (config.features.dynamic_cells, DYNAMIC_CELLS_TO_CORE),
    ):
        for name, paths in table.items():
            for path in paths:
                _set_core(options, path, getattr(section, name))
    # The IMU is the body frame (EuRoC's convention: imu0's T_BS is the identity).
    options.imu.T_body_cam = np.asarray(camera.T_body_cam, dtype=np.float64)
    if vocabulary is not None:
        options.vocabulary_path = str(vocabulary)
    try:
        options.check()
    except ValueError as exc:
        raise InputError("tracking config", str(exc)) from exc
    return options


#: Front-end class -> the front end whose shipped vocabulary (``slslam.place``) it uses. By class
#: name, as front ends share no base class. SuperPoint is absent: no vocabulary ships for it.
_SHIPPED_VOCABULARY_FOR = {"Orb": "orb", "XFeat": "xfeat"}


def _vocabulary_for(config: Config, frontend: Any) -> Path | None:
    """The vocabulary relocalisation uses: the configured file, else the one shipped for the
    front end (ORB, XFeat); None (no relocalisation) otherwise."""
    t = config.tracking
    if not t.relocalisation:
        return None
    if t.vocabulary_path:
        from slslam.files import special_file_kind
        from slslam.place import check_vocabulary_records

        path = Path(t.vocabulary_path).expanduser()
        kind = special_file_kind(path)
        if kind == "missing":
            raise InputError(path, "tracking.vocabulary_path: vocabulary file not found")
        if kind is not None:  # a FIFO or device would block or never end the core's read
            raise InputError(path, f"tracking.vocabulary_path: is {kind}, not a vocabulary file")
        check_vocabulary_records(path)  # word weights in range, before the core loads it
        return path
    from slslam.place import default_vocabulary_path

    shipped = _SHIPPED_VOCABULARY_FOR.get(type(frontend).__name__)
    if shipped is None:
        log.warning(
            "no bag-of-words vocabulary for %s descriptors (tracking.vocabulary_path; "
            "`slslam vocab train`): relocalisation is off",
            type(frontend).__name__,
        )
        return None
    try:
        return default_vocabulary_path(shipped)
    except SlslamError as exc:  # an installation without package data: track without it
        log.warning("%s: relocalisation is off", exc)
        return None


#: The tracking options AdaptToRig turns to the camera's frame rate and focal length.
RIG_ADAPTED_OPTIONS = (
    "frame_rate_hz",
    "keyframe_max_frames",
    "keyframe_min_frames",
    "keyframe_min_frames_noisy",
    "weak_keyframe_frames",
    "projected_max_frames",
    "recently_lost_frames",
    "lost_motion_frames",
    "new_map_after_lost_frames",
    "lost_velocity_decay",
    "unaligned_max_turn_deg_per_frame",
    "search_radius_px",
    "line_search_px",
    "projection_search_px",
    "projection_cell_px",
)


class Tracker:
    """Stereo point-line visual SLAM.

    Args:
        camera: rectified stereo intrinsics and baseline (``EurocSequence.camera``).
        config: configuration (``slslam.load_config``); ``slslam.default_config()`` (ORB
            with its preset) when None.
        frontend: a point front end with ``detect(image) -> Keypoints`` and the capabilities it
            declares (:class:`slslam.features.PointFrontEnd`; a ``TypeError`` names what is
            wrong with one that does not fit); by default the one the config names (SuperPoint,
            or ORB when no SuperPoint weights are configured).
    """

    def __init__(
        self,
        camera: RectifiedStereoCamera,
        config: Config | None = None,
        frontend: PointFrontEnd | None = None,
        load_map: str | Path | None = None,
        localise_only: bool = False,
    ) -> None:
        self.config = config or default_config()
        self.camera = camera
        self.frontend: PointFrontEnd = (
            frontend if frontend is not None else make_point_frontend(self.config.features)
        )
        self.frontend_name = type(self.frontend).__name__
        # What its detect takes, as it declares (slslam.features.frontend; defaults for a front
        # end that leaves an attribute out; TypeError for one without detect).
        capabilities = frontend_capabilities(self.frontend)
        # Whether the point front end sees the pair smoothed for the core (ORB, XFeat).
        self._detect_smoothed = capabilities.smoothed_input
        self._low_light = LowLightEnhancer(self.config.features.low_light)
        grid = self.config.features.grid
        self._grid = _core.GridLimitOptions()
        self._grid.cell_size_px = grid.cell_size_px
        self._grid.max_per_cell = grid.max_per_cell
        # Low-texture fallback for learned detectors: detect at a lower threshold and let the
        # grid keep the weak keypoints only in cells without a strong one (ORB does it inside).
        self._weak_threshold: float | None = None
        features = self.config.features
        threshold = capabilities.detection_threshold
        accepts = capabilities.detect_takes_threshold
        self._detect_selects = capabilities.detect_takes_select
        # A front end that takes denoised_above_noise (ORB, XFeat) is told that the image it
        # sees came through this tracker's smoothing, so that it does not check the noise again.
        self._detect_denoised = self._detect_smoothed and capabilities.detect_takes_denoised
        if features.low_texture_fallback and threshold is not None and accepts:
            self._weak_threshold = threshold * features.low_texture_ratio
            self._grid.strong_score = threshold
        self.vocabulary = _vocabulary_for(self.config, self.frontend)
        options = _core_options(camera, self.config, self.vocabulary)
        if localise_only and load_map is None:
            raise InputError("--localise-only", "localisation-only mode needs a map (--load-map)")
        options.localise_only = localise_only
        self._core = _core.TrackerCore(options, _line_options(self.config))
        # The options the core runs with (the counts in frames at the camera's rate, the pixel
        # windows at its focal length: tracking.reference_rate_hz, reference_focal_px).
        self._rig_options = _core.adapt_to_rig(options)
        # tracking.projected_max_frames: frames go to the core without keypoints when it will
        # likely place the map's points itself (_detect_ahead); the descriptor kind of the empty
        # set is the front end's own, found on the first detection.
        self._no_keypoints: Keypoints | None = None
        # _detect_ahead's choices for the frames whose results it may not know yet (index ->
        # detected, expected keyframe).
        self._ahead_choices: dict[int, tuple[bool, bool]] = {}
        if load_map is not None:
            from slslam.files import require_regular_file

            # a FIFO, device or folder is refused before the core opens it
            path = require_regular_file(Path(load_map).expanduser(), InputError, "map file")
            try:
                self._core.load_map(str(path))
            except (ValueError, RuntimeError) as exc:
                raise InputError(path, str(exc)) from None
        self._results: list[TrackResult] = []
        # IMU samples given (add_imu) and not yet handed to the core: each frame's core call
        # first takes those up to its timestamp (so offline runs may give them all at once).
        self._imu_pending: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._imu_last_t_ns: int | None = None
        # (the samples are on the IMU's clock: t_cam = t_imu + tracking.imu.time_offset_s)
        self._imu_offset_ns = ns_from_seconds(self.config.tracking.imu.time_offset_s)
        # The right image on a helper thread, and the left image's lines beside the point front
        # end (a thread of their own: LSD + LBD cost about what ORB of both images costs, and
        # XFeat's network half of it); with the right image's lines every frame
        # (right_lines_on_keyframes false) the core extracts both side by side instead.
        tracking = self.config.tracking
        self._threads = FrontEndThreads(
            lines=tracking.use_lines and tracking.right_lines_on_keyframes
        )
        self._closed = False
        self._to_gray = GrayImageReader()  # 16-bit scale chosen on the first 16-bit frame
        #: The rectified left image and its keypoints (N, 2) of the latest result (viewers).
        self.last_image: np.ndarray | None = None
        self.last_keypoints_uv: np.ndarray | None = None

    @property
    def _lines_side(self) -> ThreadPoolExecutor | None:
        """The lines thread (``FrontEndThreads.lines``); set to None, the core extracts the
        left image's lines itself (tests compare the two)."""
        return self._threads.lines

    @_lines_side.setter
    def _lines_side(self, executor: ThreadPoolExecutor | None) -> None:
        self._threads.lines = executor

    # -- per frame -----------------------------------------------------------------------------
    def add_imu(self, t_ns: np.ndarray, gyro_radps: np.ndarray, acc_mps2: np.ndarray) -> None:
        """IMU samples for the visual-inertial tracking (``tracking.imu`` in
        configs/default.yaml, docs/imu.md): ``t_ns`` (N,) integer nanoseconds on the IMU's clock
        (the frames' clock shifted by ``tracking.imu.time_offset_s``: t_cam = t_imu + offset),
        increasing (float seconds are refused: convert with
        :func:`slslam.timestamps.ns_from_seconds`);
        ``gyro_radps`` and ``acc_mps2`` (N, 3) in the IMU (body) frame, angular rate and specific
        force. Give them before the frames they precede (online) or all at once before the first
        frame (offline); each frame uses those up to its timestamp. Bad samples raise
        ``InputError``; with ``tracking.imu.enabled: false`` they are ignored."""
        t = np.asarray(t_ns).reshape(-1)
        if t.size and not np.issubdtype(t.dtype, np.integer):
            raise InputError(
                "IMU samples", f"times must be integer nanoseconds (int64), got dtype {t.dtype}"
            )
        t = t.astype(np.int64)
        gyro = np.asarray(gyro_radps, dtype=np.float64)
        acc = np.asarray(acc_mps2, dtype=np.float64)
        n = len(t)
        if gyro.shape != (n, 3) or acc.shape != (n, 3):
            raise InputError(
                "IMU samples",
                f"{n} times need gyro and acc of shape ({n}, 3), got {gyro.shape} and {acc.shape}",
            )
        if n == 0:
            return
        if not (np.all(np.isfinite(gyro)) and np.all(np.isfinite(acc))):
            raise InputError("IMU samples", "a rate or specific force is not finite")
        last = self._imu_last_t_ns
        if np.any(np.diff(t) <= 0) or (last is not None and int(t[0]) <= last):
            raise InputError("IMU samples", "times must increase (and follow the last given)")
        self._imu_last_t_ns = int(t[-1])
        if self._imu_pending is not None:
            t0, g0, a0 = self._imu_pending
            t, gyro, acc = (np.concatenate(p) for p in ((t0, t), (g0, gyro), (a0, acc)))
        self._imu_pending = (t, gyro, acc)

    def _feed_imu(self, t_ns: int) -> None:
        """Hands the core the pending IMU samples up to the frame time ``t_ns`` (consumer
        thread)."""
        if self._imu_pending is None:
            return
        t, gyro, acc = self._imu_pending
        n = int(np.searchsorted(t, t_ns - self._imu_offset_ns, side="right"))
        if n == 0:
            return
        self._core.add_imu(t[:n], np.ascontiguousarray(gyro[:n]), np.ascontiguousarray(acc[:n]))
        self._imu_pending = (t[n:], gyro[n:], acc[n:]) if n < len(t) else None

    def _smooth(self, image: np.ndarray) -> np.ndarray:
        """A noisy (dark) image smoothed (``tracking.denoise_above_noise``), else the image.
        Done once here, on the front end's threads: the detector (unless its ``smoothed_input``
        is False), the lines and the stereo matching all see the smoothed pair, and are told so
        (``denoised_above_noise``, ``denoised``): none of them estimates the noise again or
        blurs it a second time."""
        above = self.config.tracking.denoise_above_noise
        return _core.smooth_if_noisy(image, above) if above > 0.0 else image

    def _smooth_and_detect(self, image: np.ndarray) -> tuple[np.ndarray, Keypoints]:
        """The image as the core gets it (smoothed when noisy) and its keypoints."""
        smoothed = self._smooth(image)
        return smoothed, self._detect_either(image, smoothed)

    def _detect_either(self, raw: np.ndarray, smoothed: np.ndarray) -> Keypoints:
        """Keypoints detected on the smoothed image or, for a front end whose
        ``smoothed_input`` is False (SuperPoint), on the image as it came."""
        return self._detect(smoothed if self._detect_smoothed else raw)

    def _detect(self, image: np.ndarray) -> Keypoints:
        """The front end's keypoints of ``image`` limited per grid cell (features.grid). A front
        end whose ``detect`` takes ``select`` (XFeat) applies the limit itself, before it samples
        descriptors: only the kept keypoints are described (the same keypoints and descriptors)."""

        def limit(uv: np.ndarray, scores: np.ndarray) -> np.ndarray:
            keep = _core.grid_limit(
                np.ascontiguousarray(uv, dtype=np.float32),
                np.ascontiguousarray(scores, dtype=np.float32),
                image.shape[1],
                image.shape[0],
                self._grid,
            )
            return np.asarray(keep, dtype=np.int64)

        options: dict = {}
        if self._weak_threshold is not None:
            options["threshold"] = self._weak_threshold
        if self._detect_denoised and self.config.tracking.denoise_above_noise > 0.0:
            options["denoised_above_noise"] = self.config.tracking.denoise_above_noise
        detect = cast(Any, self.frontend).detect  # (its keywords: as it declares them)
        if self._detect_selects:
            return cast(Keypoints, detect(image, select=limit, **options))
        keypoints = cast(Keypoints, detect(image, **options))
        if len(keypoints) == 0:
            return keypoints
        return keypoints.select(limit(keypoints.uv, keypoints.scores))

    def track(
        self,
        left: np.ndarray,
        right: np.ndarray,
        timestamp: float | None = None,
        *,
        t_ns: int | None = None,
    ) -> TrackResult:
        """Tracks one rectified stereo pair taken at ``timestamp`` seconds, or exactly at ``t_ns``
        integer nanoseconds (give one; a reader's frames carry ``t_ns``).

        Images as ``cv2.imread`` gives them: uint8 gray (H x W) as they are; uint8 BGR / BGRA
        (H x W x 3 / 4) to gray with OpenCV's weights (0.299 R + 0.587 G + 0.114 B); 16-bit gray
        (``cv2.IMREAD_UNCHANGED``) to 8 bits by 1/256, or by 1/16 when the first 16-bit frame
        holds nothing above 4095 (12-bit data), the same scale for the whole run
        (:class:`~slslam.datasets.images.GrayImageReader`). Bad input (another type or shape,
        a size other than the calibration's, non-finite or decreasing time) raises
        ``InputError``; a frame that cannot be tracked (black, blurred, textureless) returns
        state LOST.
        """
        if self._closed:
            raise RuntimeError("the tracker is closed")
        index = len(self._results)
        stamp = _frame_time_ns(f"frame {index}", timestamp, t_ns)
        previous = self._results[-1].t_ns if self._results else None
        return self._track_prepared(self._prepare(index, left, right, stamp, previous))

    def track_stream(
        self,
        frames: Iterable[tuple[np.ndarray, np.ndarray, float] | SupportsStereoFrame],
        pipeline: bool = True,
        frames_ahead: int | None = None,
    ) -> Generator[TrackResult, None, None]:
        """Tracks frames in order, yielding each frame's result: (left, right, timestamp [s])
        triples, or objects with ``left``, ``right`` and ``t_ns`` [ns] (a reader's
        ``StereoFrame``: its exact time).

        With ``pipeline`` the point front end and the stereo matching of the next frames (and
        reading them from ``frames``) run on a worker thread while the core tracks frame k: at most
        ``frames_ahead`` frames prepared and not yet taken by the core (default
        ``tracking.pipeline_frames_ahead``; 1: frame k+1 only), results in input order and
        equal to ``track`` in a loop. More than one lets the front end go on while the core
        spends a keyframe's local mapping, so more frames go through a second; a frame the
        worker takes early waits in the queue instead of at its source. An error in frame k (bad
        input, a failing reader) is raised after the results of the frames before it. Stopping
        the iteration early (break, an exception, a signal) stops the worker after the frame it
        is preparing; frames prepared and not yet tracked are dropped.
        """
        if self._closed:
            raise RuntimeError("the tracker is closed")
        if not pipeline:
            for frame in frames:
                left, right, seconds, ns = _unpack_frame(frame)
                yield self.track(left, right, seconds, t_ns=ns)
            return
        ahead = self.config.tracking.pipeline_frames_ahead if frames_ahead is None else frames_ahead
        if isinstance(ahead, bool) or not isinstance(ahead, numbers.Integral) or ahead < 1:
            raise ValueError(f"frames_ahead must be an integer >= 1, got {ahead!r}")
        ahead = int(ahead)  # numpy integers too
        first = len(self._results)
        previous = self._results[-1].t_ns if self._results else None

        def prepare(
            position: int, frame: tuple[np.ndarray, np.ndarray, float] | SupportsStereoFrame
        ) -> _Prepared:
            """The worker's part of one frame (slslam.tracking.pipeline.run_ahead)."""
            nonlocal previous
            left, right, seconds, ns = _unpack_frame(frame)
            stamp = _frame_time_ns(f"frame {first + position}", seconds, ns)
            prepared = self._prepare(first + position, left, right, stamp, previous)
            previous = stamp
            return prepared

        with closing(run_ahead(frames, prepare, ahead, name="slslam-frontend")) as prepared:
            for frame in prepared:
                yield self._track_prepared(frame)

    def _prepare(
        self,
        index: int,
        left: np.ndarray,
        right: np.ndarray,
        t_ns: int,
        previous: int | None,
    ) -> _Prepared:
        """Checks one frame, runs the point front end on both images, or on the left one with
        ``tracking.stereo_row_search``, and the stereo matching (thread-safe: no state of the
        tracker is written)."""
        where = f"frame {index}"
        try:
            left = check_gray_image(self._to_gray.convert(left, "left image"))
            right = check_gray_image(self._to_gray.convert(right, "right image"))
        except ValueError as exc:
            raise InputError(where, str(exc)) from exc
        expected = (self.camera.height, self.camera.width)
        if left.shape != expected or right.shape != expected:
            raise InputError(
                where,
                f"image sizes {left.shape[::-1]} / {right.shape[::-1]} differ from the "
                f"calibration's {expected[::-1]} (width x height)",
            )
        if previous is not None and t_ns <= previous:
            raise InputError(where, f"time {t_ns} ns does not increase (previous {previous} ns)")
        return self._prepare_checked(
            index, t_ns, left, right, detect=self._detect_ahead(index), lines=None
        )

    def _prepare_checked(
        self,
        index: int,
        t_ns: int,
        left: np.ndarray,
        right: np.ndarray,
        detect: bool,
        lines: Future | None,
    ) -> _Prepared:
        """_prepare's work on checked gray images: the point front end (unless ``detect`` is
        False: ``tracking.projected_max_frames``, the core then places the map's points in the
        frame or hands it back), the left image's lines (``lines``: extracted already) and the
        stereo matching."""
        where = f"frame {index}"
        start = time.perf_counter()
        left, right = self._low_light.pair(left, right)  # features.low_light (none: unchanged)
        raw_left, raw_right = left, right
        # The right image and the left image's lines on helper threads meanwhile (LSD, ORB,
        # onnxruntime and the smoothing release the GIL). The left image is smoothed first, once,
        # for its lines, its detection and the core.
        row_search = self.config.tracking.stereo_row_search
        # (row search: left only, the core searches each keypoint's patch along its right row)
        right_side = self._threads.submit_right(
            self._smooth if row_search or not detect else self._smooth_and_detect, right
        )
        left = self._smooth(left)
        if lines is None and self._threads.lines is not None and self._lines_ahead():
            lines = self._threads.submit_lines(self._core.extract_left_lines, left, denoised=True)
        if detect:
            kl = self._detect_either(raw_left, left)
            if self._no_keypoints is None:
                self._no_keypoints = kl.select(np.zeros(0, dtype=np.int64))
        else:
            assert self._no_keypoints is not None  # (_detect_ahead: only after a detection)
            kl = self._no_keypoints
        if row_search or not detect:
            right = cast(np.ndarray, right_side.result())  # _smooth
            kr = kl.select(np.zeros(0, dtype=np.int64))
        else:
            right, kr = cast(tuple[np.ndarray, Keypoints], right_side.result())
        inference_ms = (time.perf_counter() - start) * 1e3
        try:
            left_lines = lines.result() if lines is not None else None
        except (ValueError, RuntimeError) as exc:  # named with its frame, as the core's errors
            raise RuntimeError(f"{where}: line extraction: {exc}") from exc
        # Stereo matching here, not in the core: in a pipeline it runs ahead, beside the core's
        # tracking of the frame before (the same frame either way; TrackerCore.prepare).
        stereo = self._core.prepare(
            index,
            t_ns,
            left,
            right,
            np.ascontiguousarray(kl.uv, dtype=np.float32).reshape(-1, 2),
            np.ascontiguousarray(kl.descriptors),
            np.ascontiguousarray(kr.uv, dtype=np.float32).reshape(-1, 2),
            np.ascontiguousarray(kr.descriptors),
            left_lines,
            keypoints_pending=not detect,
            noisy=left is not raw_left,  # (smoothed as noisy: tracking.unaligned_sigma_factor)
            denoised=True,  # (both through self._smooth: the core need not check them again)
        )
        front_ms = (time.perf_counter() - start) * 1e3
        return _Prepared(
            index,
            t_ns,
            left,
            kl,
            inference_ms,
            front_ms,
            stereo,
            raw_left,
            raw_right,
            lines,
        )

    def _track_prepared(self, frame: _Prepared) -> TrackResult:
        """The core's part of one frame (GIL released inside): tracking and local mapping (and
        the left image's lines when no lines thread extracted them)."""
        index, where = frame.index, f"frame {frame.index}"
        self._feed_imu(frame.t_ns)
        start = time.perf_counter()
        front_ms = frame.front_ms
        out = self._core.track_prepared(frame.stereo)
        if out.needs_keypoints:
            # tracking.projected_max_frames: the core could not place the map's points in this
            # frame (or it would become a keyframe): again, with its keypoints detected
            # (nothing changed in the core meanwhile).
            redo_start = time.perf_counter()
            frame = self._prepare_checked(
                frame.index,
                frame.t_ns,
                frame.raw_left,
                frame.raw_right,
                detect=True,
                lines=frame.lines,
            )
            out = self._core.track_prepared(frame.stereo)
            front_ms += (time.perf_counter() - redo_start) * 1e3 - frame.front_ms  # (counted once)
        kl = frame.left_keypoints
        inference_ms = frame.inference_ms
        T_world_cam = np.linalg.inv(out.cam_from_world)
        if not np.all(np.isfinite(T_world_cam)):  # never hand out a NaN pose
            raise RuntimeError(f"{where}: the tracker produced a non-finite pose")
        timings = StageTimings(
            inference=inference_ms,
            line_extraction=out.line_extraction_ms,
            stereo_matching=out.stereo_matching_ms,
            matching=out.matching_ms,
            optimisation=out.optimisation_ms,
            mapping=out.mapping_ms,
            relocalisation=out.relocalisation_ms,
            # The frame's own work: front end plus core (in the pipeline the two overlap others).
            total=front_ms + (time.perf_counter() - start) * 1e3,
        )
        counts = FrameCounts(
            keypoints=out.projected_keypoints or len(kl),
            lines=out.lines,
            matched_points=out.matched_points,
            inlier_points=out.inlier_points,
            matched_lines=out.matched_lines,
            inlier_lines=out.inlier_lines,
            keyframe=int(out.keyframe),
            map=out.map_index,
            weighted_inliers=round(float(out.weighted_inliers), 3),
            masked_keypoints=out.masked_keypoints,
            projected=int(out.projected_keypoints > 0),
            imu=int(out.imu_initialised),
            position_sigma_m=round(float(out.position_sigma_m), 6),
            **_inertial_columns(out),
        )
        result = TrackResult(index, frame.t_ns, out.state, T_world_cam, timings, counts)
        self.last_image, self.last_keypoints_uv = frame.left, kl.uv
        self._results.append(result)
        return result

    def _detect_ahead(self, index: int) -> bool:
        """Whether the point front end runs on frame ``index`` ahead of the core: always, unless
        ``tracking.projected_max_frames``; then the core tracks a frame given with its keypoints
        on them and one given without on the map's points placed in it, or hands it back when it
        cannot (detected then, on the core's thread: the cost of a wrong choice). Detected here:
        after a result that was not tracked or held fewer point inliers than
        ``projection_min_inliers``, when ``projected_max_frames`` frames since the last detected
        one were not, right after a keyframe (the core detects that frame: its inliers are the
        keyframe rule's reference), and when a keyframe is due (as many frames since the last
        keyframe as the median of the last gaps between keyframes; a keyframe needs detected
        keypoints).

        The choice reads only the results of frames up to ``index - pipeline_frames_ahead - 1``,
        which a pipeline's worker always knows (it runs at most ``pipeline_frames_ahead`` frames
        ahead of the core), and its own choices for the frames since. So it is the same in a
        pipeline and one frame at a time, and so are the poses (with ``track_stream``'s
        ``frames_ahead`` above the configured value the worker may know fewer and choose
        otherwise)."""
        tracking = self.config.tracking
        max_frames = self._rig_options.projected_max_frames  # at the camera's rate
        if max_frames <= 0 or self._no_keypoints is None:
            return True
        lag = tracking.pipeline_frames_ahead + 1
        known = [r for r in self._results[-64:] if r.index <= index - lag]  # (a copy)
        last = known[-1] if known else None
        for old in [k for k in self._ahead_choices if k < index - 64]:
            del self._ahead_choices[old]
        since = [
            (k, choice) for k, choice in self._ahead_choices.items() if index - lag < k < index
        ]

        def choose(detect: bool, keyframe: bool = False) -> bool:
            self._ahead_choices[index] = (detect, keyframe)
            return detect

        if (
            last is None
            or last.state != "OK"
            or last.counts.inlier_points < tracking.projection_min_inliers
        ):
            return choose(True)
        detected = [r.index for r in known if not r.counts.projected]
        detected += [k for k, (detect, _) in since if detect]
        if not detected or index - max(detected) > max_frames:
            return choose(True)
        keyframes = [r.index for r in known if r.counts.keyframe]
        if len(keyframes) < 2:
            return choose(False)
        gaps = np.diff(keyframes[-6:])
        expected = [k for k, (_, keyframe) in since if keyframe]
        last_keyframe = max([keyframes[-1], *expected])
        if index - last_keyframe == 1:  # (the core detects the frame after a keyframe)
            return choose(True)
        if index - last_keyframe >= max(1, int(np.median(gaps))):
            return choose(True, keyframe=True)
        return choose(False)

    def _lines_ahead(self) -> bool:
        """Whether the left image's lines are extracted beside the point front end: always,
        unless ``tracking.lines_on_demand``; then when the core will likely ask for them (the
        newest result known here was not tracked, a new map or a relocalisation, or had fewer
        point inliers than ``lines_on_demand_inliers``). The guess decides time only: the core
        asks for a frame's lines by its own rule, and lines extracted ahead are those it would
        extract (the pipeline may guess from an older result than a sequential run)."""
        tracking = self.config.tracking
        if not tracking.lines_on_demand:
            return True
        last = self._results[-1] if self._results else None
        return (
            last is None
            or last.state != "OK"
            or last.counts.inlier_points < tracking.lines_on_demand_inliers
        )

    # -- results -------------------------------------------------------------------------------
    def rig_adapted_options(self) -> dict[str, float]:
        """The tracking options that follow the rig, as the core runs with them (the counts in
        frames at ``tracking.frame_rate_hz``, the pixel windows at the camera's fx; equal to the
        config's where the rig is the reference one or the references are 0)."""
        o = self._rig_options
        return {name: getattr(o, name) for name in RIG_ADAPTED_OPTIONS}

    @property
    def results(self) -> list[TrackResult]:
        """Every frame's result so far, in input order."""
        return list(self._results)

    def trajectory(self) -> tuple[np.ndarray, np.ndarray, list[str]]:
        """(timestamps (N,), poses T_world_cam (N, 4, 4), states) for every frame so far; the
        poses of frames whose state is not in ``TRACKED_STATES`` are predictions, not
        estimates."""
        stamps = np.array([r.timestamp for r in self._results])
        poses = np.array([r.T_world_cam for r in self._results]).reshape(-1, 4, 4)
        return stamps, poses, [r.state for r in self._results]

    def map(self, settle: bool = True) -> MapData:
        """The sparse map of every map of the atlas. ``settle`` waits for local mapping first
        (and applies an overlapped local BA, ``tracking.mapping_overlap``); False takes the map
        as it stands and changes nothing, so a viewer's snapshots leave the poses as they were."""
        m = self._core.map(settle)
        names = {f.name for f in dataclasses.fields(MapStats)} - {"loop_events", "imu"}
        events = tuple(
            LoopEvent(
                int(e["frame_index"]),
                int(e["candidate_frame_index"]),
                bool(e["merge"]),
                float(e["correction_m"]),
            )
            for e in m["loop_events"]
        )
        return MapData(
            np.asarray(m["points"]).reshape(-1, 3),
            np.asarray(m["lines"]).reshape(-1, 6),
            int(m["keyframes"]),
            int(m["maps"]),
            MapStats(
                **{k: m[k] for k in names},
                loop_events=events,
                imu={
                    k: (
                        np.asarray(v, dtype=float).reshape(-1).round(9).tolist()
                        if k.endswith(("_radps", "_mps2"))
                        else v
                    )
                    for k, v in m["imu"].items()
                },
            ),
        )

    def final_trajectory(self) -> FinalTrajectory:
        """Every estimated frame pose in the final map: after loop correction, map merges and
        global bundle adjustment (each frame follows its reference keyframe). Waits for local
        mapping first."""
        t = self._core.trajectory()
        R_cam_world = np.asarray(t["cam_from_world_rotation"]).reshape(-1, 3, 3)
        t_cam_world = np.asarray(t["cam_from_world_translation"]).reshape(-1, 3)
        T_world_cam = np.tile(np.eye(4), (len(R_cam_world), 1, 1))
        T_world_cam[:, :3, :3] = np.transpose(R_cam_world, (0, 2, 1))
        T_world_cam[:, :3, 3] = -np.einsum("nji,nj->ni", R_cam_world, t_cam_world)
        return FinalTrajectory(
            np.asarray(t["index"], dtype=int),
            np.asarray(t["t_ns"], dtype=np.int64),
            np.asarray(t["map_index"], dtype=int),
            T_world_cam,
        )

    def save_map(self, path: str | Path) -> Path:
        """Writes every live map of the atlas to ``path`` (slslam's versioned, checksummed binary
        map file; written to a temporary name and renamed). Waits for local mapping first."""
        from slslam import __version__

        path = Path(path).expanduser()
        try:
            self._core.save_map(str(path), __version__)
        except (ValueError, RuntimeError) as exc:
            raise InputError(path, str(exc)) from None
        return path

    def close(self) -> None:
        """Finishes local mapping. The results and the map stay readable."""
        if not self._closed:
            self._threads.shutdown()
            self._core.flush()
            self._closed = True

    def __enter__(self) -> Tracker:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
